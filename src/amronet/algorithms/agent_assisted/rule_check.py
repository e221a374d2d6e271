"""The compiled step's view of the run's drop rule: whether any agent acts this step (:mod:`.rule_kernels`).

:class:`RuleCheck` reads the controller's drop rule and switches once, and each step hands
:func:`~amronet.algorithms.agent_assisted.rule_kernels.rule_quiet` what the controller's
:meth:`~amronet.algorithms.agent_assisted.drop_switches.DropSwitches._view` would show the rule: the same arrays, the
known relays (the settling routers too), the agents' contact with a base station and their best link margins where
the rule reads them.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from amronet.algorithms.agent_assisted.drops.junction import DistanceJunction
from amronet.algorithms.agent_assisted.drops.last_reference import LastReference
from amronet.algorithms.agent_assisted.drops.link_quality import LinkQuality
from amronet.algorithms.agent_assisted.drops.radius import Radius
from amronet.algorithms.agent_assisted.drops.strip_goals import StripGoals
from amronet.algorithms.agent_assisted.rule_kernels import (
    JUNCTION,
    LIMITS,
    LINK,
    LOSING,
    PAPER,
    RADIUS,
    RuleBooks,
    RuleInputs,
    RuleStep,
    rule_commit,
    rule_quiet,
)
from amronet.algorithms.common.references import best_reference_margin
from amronet.engine.network import agents_connected
from amronet.engine.robots import State

if TYPE_CHECKING:
    from amronet.algorithms.agent_assisted.fast import AgentControls
    from amronet.algorithms.base import StepInput

__all__ = ["RULE_CODES", "RuleCheck", "paper_rule_step"]

RULE_CODES: dict[type, int] = {LastReference: LOSING, StripGoals: LOSING, Radius: RADIUS, DistanceJunction: JUNCTION,
                               LinkQuality: LINK}
"""The drop rules the check knows, by class (a subclass may decide otherwise: the controller's Python then runs)."""

_NONE = np.zeros(0)


class RuleCheck:
    """Whether any agent acts this step under the controller's drop rule and switches (see the module docstring).

    Args:
        controller: The compiled step's controller; its rule's class must be one of :data:`RULE_CODES`.
    """

    def __init__(self, controller: AgentControls) -> None:
        c = self.controller = controller
        rule = c.drop_rule
        a = len(c.agents)
        self.code = RULE_CODES[type(rule)]
        limits = dict.fromkeys(LIMITS, np.nan)
        r_c = rule.context.r_c
        samples = np.zeros((a, 3, 2))
        smoothed = np.zeros(a)
        if self.code == RADIUS:
            limits.update(far=rule.params.radius * r_c,
                          every_s=np.nan if rule.params.every_s is None else rule.params.every_s)
        elif self.code == JUNCTION:
            p = rule.params
            limits.update(far=p.far * r_c, junction_clear=p.junction_clear * r_c, turn_clear=p.turn_clear * r_c,
                          base_clear=p.base_clear * r_c, open_range=p.open_fraction * rule.context.sensor_range,
                          cos_angle=rule.turns.cos_angle, spacing=rule.turns.spacing)
            samples = rule.turns.samples
        elif self.code == LINK:
            limits.update(drop_db=rule.params.drop_margin_db, loss_db=rule.params.loss_margin_db,
                          alpha=rule.filter.alpha)
            smoothed = rule.filter.value
        self.books = RuleBooks(self.code, bool(c.tether), float(c.r_eff), np.array([limits[k] for k in LIMITS]),
                               c.pending_until, c.reversing, getattr(rule, "last_drop", _NONE), samples,
                               np.empty_like(samples), smoothed, np.empty_like(smoothed))
        self.plain = tuple(self.books)
        self.contact = self.code == JUNCTION or c.reverse_after_s is not None
        """Whether the check reads the agents' contact with a base station."""
        self.base_xy = c.swarm.xy[c.bases]  # (base nodes never move)
        self._no_contact = np.zeros(a, dtype=np.bool_)
        self.last_contact = self._no_contact
        """The agents' contact with a base station as :meth:`quiet` last read it (where :attr:`contact` holds)."""
        self._no_margin = np.full(a, -np.inf)
        self._contact = np.zeros(a, dtype=np.bool_)
        self._best = np.full(a, -np.inf)

    @property
    def stretches(self) -> bool:
        """Whether the check can be made inside a quiet stretch: always.

        Reverse drops too: the stretch keeps their books (:class:`~.stretch_books.ReverseDrop`).
        """
        return True

    def in_stretch(self, first: int, dt: float) -> RuleStep:
        """The check as a quiet stretch makes it (:func:`~.rule_kernels.rule_acts`), from step ``first`` on.

        Only where no router settles (the known relays are the deployed nodes) and :attr:`stretches` holds.
        """
        c = self.controller
        self._check_books()
        return RuleStep(self.plain, c.deployed_nodes()[1], self.base_xy, c.bases, c.swarm.relaying, first, dt,
                        self._contact, self._best)

    @property
    def reads_margins(self) -> bool:
        """Whether the check reads the agents' link margins (the link-quality rule)."""
        return self.code == LINK

    @staticmethod
    def knows(controller: AgentControls) -> bool:
        """Whether the controller's drop rule is one the check knows."""
        return type(controller.drop_rule) in RULE_CODES

    def quiet(self, now: StepInput, scans: np.ndarray) -> bool:
        """Whether no agent acts this step; if none does, the rule's books are kept as its own steps keep them.

        ``now``: the step's input (its table); ``scans``: the agents' readings this step.
        """
        c = self.controller
        sw = c.swarm
        is_ref, relay_xy = c.deployed_nodes()
        if c.settle_at:
            relay_xy = np.concatenate([relay_xy, sw.xy[sw.state == State.DROPPED]])
        contact = (agents_connected(now.table, c.agents, c.bases, sw.relaying) if self.contact
                   else self._no_contact)
        self.last_contact = contact
        best = best_reference_margin(now.table, c.agents, is_ref) if self.code == LINK else self._no_margin
        inputs = RuleInputs(now.t, c.agents, sw.xy, c.current, c.nearest_d, c.left, relay_xy, self.base_xy, contact,
                            best, scans)
        self._check_books()
        if not rule_quiet(self.plain, tuple(inputs)):
            return False
        rule_commit(self.plain)
        return True

    def _check_books(self) -> None:
        """Build the books again where the controller replaced one of its arrays (they are updated in place)."""
        c, kept = self.controller, self.books
        if kept.pending_until is not c.pending_until or kept.reversing is not c.reversing:
            self.books = kept._replace(pending_until=c.pending_until, reversing=c.reversing)
            self.plain = tuple(self.books)



def paper_rule_step(dt: float) -> RuleStep:
    """A quiet stretch's :class:`~.rule_kernels.RuleStep` under the paper's rule alone: no check (the same types)."""
    none, flags, paths = np.zeros(0), np.zeros(0, dtype=np.bool_), np.zeros((0, 3, 2))
    books = RuleBooks(PAPER, False, 0.0, np.zeros(len(LIMITS)), none, flags, none, paths, paths, none, none)
    return RuleStep(tuple(books), np.zeros((0, 2)), np.zeros((0, 2)), np.zeros(0, dtype=np.int64), flags, 0, dt, flags,
                    none)
