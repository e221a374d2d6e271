"""``distance-junction``: MARBLE's beacon rules (DARPA SubT; ``dan-riley/bobcat``, ``src/monitors.py``).

An agent drops a router only while it is **in contact** with a base station (it has a path through the network),
never within ``base_clear`` of a base node, and then when any of these holds:

* **distance**: it is farther than ``far`` from the nearest known relay;
* **junction**: its own range scan shows a junction (at least three separate openings: runs of beams that read at
  least ``open_fraction`` of the sensor range, around the ring) and no relay is within ``junction_clear``;
* **turn**: its path turned by more than ``turn_angle_deg`` over ``turn_travel`` of travel (the directions of the
  two halves of its last ``turn_travel`` metres, sampled from odometry) and no relay is within ``turn_clear``.

Distances are straight lines between known positions and are given as fractions of ``r_c``. MARBLE's numbers are for
tunnel radios of hundreds of metres: drop at 30 m from the nearest beacon, junctions unless one is within 10 m,
turns unless one is within 15 m, never within 10 m of the anchor, turns of 30 degrees over 4 m. We keep their
ratios to the drop distance (``far`` 0.9 ``r_c``: ``junction_clear`` 0.3, ``turn_clear`` 0.45, ``base_clear`` 0.3)
but not the turn's 4 m, which would be 0.12 ``r_c`` here and call every wobble of an indoor path a turn: turns are
judged over ``turn_travel`` = 0.5 ``r_c``.
"""

from __future__ import annotations

from typing import Annotated

import numpy as np
from pydantic import BaseModel, ConfigDict, Field

from amronet.algorithms.agent_assisted.drops.base import DROP_RULES, AgentView, DropContext, DropRule
from amronet.algorithms.agent_assisted.rule_kernels import junction_causes

__all__ = ["DistanceJunction", "DistanceJunctionParams", "PathTurns"]

Fraction = Annotated[float, Field(strict=True, ge=0, le=2, allow_inf_nan=False)]


class DistanceJunctionParams(BaseModel):
    """Parameters of the distance-junction rule (distances as fractions of ``r_c``).

    Attributes:
        far: Drop when farther than this from the nearest known relay.
        junction_clear: At a junction, drop unless a relay is within this.
        turn_clear: On a turn, drop unless a relay is within this.
        base_clear: Never drop within this of a base node.
        turn_angle_deg: A turn changes the heading of the path by more than this, degrees.
        turn_travel: ... over this much travel.
        open_fraction: A beam is open when it reads at least this fraction of the sensor range.
    """

    model_config = ConfigDict(extra="forbid", frozen=True)

    far: Annotated[float, Field(strict=True, gt=0, le=2, allow_inf_nan=False)] = 0.9
    junction_clear: Fraction = 0.3
    turn_clear: Fraction = 0.45
    base_clear: Fraction = 0.3
    turn_angle_deg: Annotated[float, Field(strict=True, gt=0, lt=180, allow_inf_nan=False)] = 30.0
    turn_travel: Annotated[float, Field(strict=True, gt=0, le=10, allow_inf_nan=False)] = 0.5
    open_fraction: Annotated[float, Field(strict=True, gt=0, le=1, allow_inf_nan=False)] = 0.95


class PathTurns:
    """Turns of each agent's path from odometry: the heading change between the two halves of its last stretch.

    Positions are sampled every ``travel / 2`` metres of straight-line progress; a turn is seen when the direction
    from the oldest to the middle sample and from the middle to the newest differ by more than ``angle``.

    Args:
        n: Number of agents.
        travel: Length of the stretch a turn is judged over, metres.
        angle_deg: Smallest heading change that is a turn, degrees.
    """

    def __init__(self, n: int, travel: float, angle_deg: float) -> None:
        self.spacing = travel / 2.0
        self.cos_angle = float(np.cos(np.radians(angle_deg)))
        self.samples = np.full((n, 3, 2), np.nan)
        """The oldest, middle and newest sample of each agent ``(A, 3, 2)`` (nan: none yet), updated in place."""
        self._new = np.empty_like(self.samples)

    def books(self) -> tuple[np.ndarray, np.ndarray, float, float]:
        """``(samples, scratch, spacing, cos_angle)``, as :func:`~.rule_kernels.junction_causes` updates them."""
        return self.samples, self._new, float(self.spacing), float(self.cos_angle)


@DROP_RULES.register("distance-junction")
class DistanceJunction(DropRule):
    """MARBLE's rules: distance from the nearest relay, junctions and turns, only while in contact."""

    Params = DistanceJunctionParams
    params: DistanceJunctionParams
    needs_contact = True
    needs_scans = True
    near_reference = False

    def __init__(self, params: DistanceJunctionParams, context: DropContext) -> None:
        super().__init__(params, context)
        self.turns = PathTurns(context.n_agents, params.turn_travel * context.r_c, params.turn_angle_deg)
        self.by_cause = {"distance": 0, "junction": 0, "turn": 0}
        """Drops by their first cause, in :func:`~.rule_kernels.junction_causes`' order."""
        r_c = context.r_c
        self._limits = (float(params.far * r_c), float(params.junction_clear * r_c), float(params.turn_clear * r_c),
                        float(params.base_clear * r_c), float(params.open_fraction * context.sensor_range))

    def decide(self, view: AgentView) -> np.ndarray:  # noqa: D102
        assert view.in_contact is not None and view.scans is not None
        cause = np.empty(len(view.xy), dtype=np.int64)  # (one compiled call)
        junction_causes(np.ascontiguousarray(view.xy, dtype=np.float64), view.relay_xy, view.base_xy,
                        np.ascontiguousarray(view.scans, dtype=np.float64), view.in_contact & view.can_drop,
                        self.turns.books(), self._limits, cause)
        drop = cause > 0
        if drop.any():
            for k, name in enumerate(self.by_cause, start=1):
                self.by_cause[name] += int(np.count_nonzero(cause == k))
        return drop

    def losing(self, view: AgentView) -> np.ndarray:
        """About to go beyond ``far`` of every relay: a tethered agent turns back there."""
        return view.nearest_relay_distance() > self.params.far * self.context.r_c

    def report(self) -> dict[str, object]:  # noqa: D102
        return {"drops_by_cause": dict(self.by_cause)}
