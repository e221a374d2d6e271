"""``link-quality``: location-free greedy deployment (paper section 6; SPAWAR's and NIST's relay deployment).

An agent hears the received signal strength of its links; the rule reads only the best link margin to any
reference it hears (dB above the usable-link threshold, :attr:`~amronet.engine.table.NeighbourTable.margin`) — no
positions, no distances. It drops a router when that margin falls below ``drop_margin_db``:

* **Smoothing**: the margin is followed by an exponential moving average with time constant ``smoothing_s``
  (restarted when the agent hears no reference), and the drop waits for the *smoothed* margin, so that one faded
  sample does not trigger a drop;
* **Hysteresis**: the drop threshold ``drop_margin_db`` sits above the loss threshold ``loss_margin_db``; a raw margin
  below the loss threshold (the link about to break, e.g. a wall stepped behind) drops at once, smoothed or not.

Why ``drop_margin_db`` is 8 dB by default: a link can lose a whole wall's loss in one step (an agent stepping
through a doorway and along the wall behind it), and no rule that reads only the present margin sees that coming;
with 8 dB of headroom, one COST 231 heavy wall (6.9 dB) does not cut an agent off. The price is paid in open space:
under the unit disk (whose RSSI follows the budget's log-distance law with exponent ``n``, 2.5 by default) the rule
fires at ``d = r_c 10^(-drop_margin_db / (10 n))``, 0.48 ``r_c`` for 8 dB and 0.76 ``r_c`` for 3 dB, where the
paper's distance rule fires at 0.95 ``r_c``. ``amronet reproduce buildings`` measures both margins. Under walls and
shadowing the rule fires where the link really is weak, which a distance rule cannot see. An agent that hears no
reference drops nothing (there is nothing to link a router to); ``agents.reverse_drop`` brings it back.
"""

from __future__ import annotations

from typing import Annotated

import numpy as np
from pydantic import BaseModel, ConfigDict, Field, model_validator

from amronet.algorithms.agent_assisted.drops.base import DROP_RULES, AgentView, DropContext, DropRule
from amronet.algorithms.common.link_quality import MarginSmoother

__all__ = ["LinkQuality", "LinkQualityParams"]

Decibels = Annotated[float, Field(strict=True, ge=0, le=60, allow_inf_nan=False)]


class LinkQualityParams(BaseModel):
    """Parameters of the link-quality rule.

    Attributes:
        drop_margin_db: Drop when the smoothed best margin to a reference falls below this (dB over the threshold).
        loss_margin_db: Drop at once when the raw best margin falls below this (dB); below ``drop_margin_db``.
        smoothing_s: Time constant of the margin's moving average, seconds (0: no smoothing).
    """

    model_config = ConfigDict(extra="forbid", frozen=True)

    drop_margin_db: Decibels = 8.0
    loss_margin_db: Decibels = 1.0
    smoothing_s: Annotated[float, Field(strict=True, ge=0, le=60, allow_inf_nan=False)] = 0.5

    @model_validator(mode="after")
    def _hysteresis(self) -> LinkQualityParams:
        if self.loss_margin_db >= self.drop_margin_db:
            raise ValueError(f"loss_margin_db ({self.loss_margin_db:g} dB) must be below drop_margin_db "
                             f"({self.drop_margin_db:g} dB): drops fire above the loss threshold")
        return self


@DROP_RULES.register("link-quality")
class LinkQuality(DropRule):
    """Drop when the smoothed best margin to a reference falls below ``drop_margin_db``."""

    Params = LinkQualityParams
    params: LinkQualityParams
    reads_positions = False

    def __init__(self, params: LinkQualityParams, context: DropContext) -> None:
        super().__init__(params, context)
        self.filter = MarginSmoother(context.n_agents, context.dt, params.smoothing_s)
        self._all = np.arange(context.n_agents)
        self._t = -np.inf
        self._weak = np.zeros(context.n_agents, dtype=bool)

    def _weak_links(self, view: AgentView) -> np.ndarray:
        if view.t != self._t:  # once per step, whether decide or losing asks first
            self._t = view.t
            smoothed = self.filter.update(self._all, view.best_margin)
            best = view.best_margin  # (comparisons with nan, no history, are false and raise nothing)
            self._weak = (smoothed < self.params.drop_margin_db) | (best < self.params.loss_margin_db)
            self._weak &= np.isfinite(best)
        return self._weak

    def decide(self, view: AgentView) -> np.ndarray:  # noqa: D102
        return self._weak_links(view) & view.can_drop

    def losing(self, view: AgentView) -> np.ndarray:
        """The links are weak (a tethered agent turns back where it would have dropped)."""
        return self._weak_links(view)

    def dropped(self, who: np.ndarray, view: AgentView) -> None:
        """A fresh router sits next to the agent: its margin history starts again."""
        self.filter.restart(who)
