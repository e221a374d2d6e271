"""``radius``: drop when farther than ``R`` from every known relay (Robotika, DARPA SubT virtual track).

Robotika's breadcrumb rule (``robotika/osgar``, ``subt/breadcrumbs.py``): a robot drops a breadcrumb when it is
farther than a set radius from every breadcrumb it knows of, the base counting as one, or (optionally) when a timer
runs out. Distances are straight lines between known positions: walls are not seen, so the rule may leave an agent
cut off behind a wall before it drops. ``R`` is given as a fraction of ``r_c``.
"""

from __future__ import annotations

from typing import Annotated

import numpy as np
from pydantic import BaseModel, ConfigDict, Field

from amronet.algorithms.agent_assisted.drops.base import DROP_RULES, AgentView, DropContext, DropRule

__all__ = ["Radius", "RadiusParams"]


class RadiusParams(BaseModel):
    """Parameters of the radius rule.

    Attributes:
        radius: ``R`` as a fraction of ``r_c``: drop when farther than ``R`` from every known relay.
        every_s: Also drop when this many seconds have passed since the agent's last drop (``None``: no timer).
    """

    model_config = ConfigDict(extra="forbid", frozen=True)

    radius: Annotated[float, Field(strict=True, gt=0, le=2, allow_inf_nan=False)] = 0.9
    every_s: Annotated[float, Field(strict=True, gt=0, allow_inf_nan=False)] | None = None


@DROP_RULES.register("radius")
class Radius(DropRule):
    """Drop when farther than ``radius * r_c`` from every known relay, or on a timer."""

    Params = RadiusParams
    params: RadiusParams
    near_reference = False

    def __init__(self, params: RadiusParams, context: DropContext) -> None:
        super().__init__(params, context)
        self.last_drop = np.zeros(context.n_agents)

    def decide(self, view: AgentView) -> np.ndarray:  # noqa: D102
        far = view.nearest_relay_distance() > self.params.radius * self.context.r_c
        if self.params.every_s is not None:
            far |= view.t - self.last_drop >= self.params.every_s
        return far & view.can_drop

    def losing(self, view: AgentView) -> np.ndarray:
        """About to leave the radius: a tethered agent turns back at ``R`` (by known positions, as it drops)."""
        return view.nearest_relay_distance() > self.params.radius * self.context.r_c

    def dropped(self, who: np.ndarray, view: AgentView) -> None:  # noqa: D102
        self.last_drop[who] = view.t
