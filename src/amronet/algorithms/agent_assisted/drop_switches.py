"""What the drop rule sees of the agents each step, and the realism switches around it.

The switches: routers that settle before they relay (``agents.drop_settle_s``) and MARBLE's reverse drop (an agent
out of contact backs up along its own path, ``agents.reverse_drop``). :class:`DropSwitches` is mixed into
:class:`~amronet.algorithms.agent_assisted.controller.AgentAssisted`; the names it declares are the controller's.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from amronet.algorithms.agent_assisted.drops import AgentView
from amronet.algorithms.common.references import best_reference_margin
from amronet.engine.network import agents_connected
from amronet.engine.robots import State

if TYPE_CHECKING:
    from collections.abc import Callable

    from amronet.algorithms.agent_assisted.drops import DropRule
    from amronet.algorithms.agent_assisted.drops.trail import Trails
    from amronet.algorithms.agent_assisted.strip_driving import StripDrivers
    from amronet.algorithms.base import StepInput
    from amronet.engine.robots import Swarm

__all__ = ["DropSwitches"]


class DropSwitches:
    """The drop rule's view of the agents, settling routers and reverse drops (a mixin of the controller)."""

    swarm: Swarm
    agents: np.ndarray
    agent_model: int
    bases: np.ndarray
    drop_rule: DropRule
    reverse_after_s: float | None
    left: np.ndarray
    pending_until: np.ndarray
    settle_at: dict[int, float]
    strips: StripDrivers | None
    contact_since: np.ndarray
    reversing: np.ndarray
    trails: Trails | None
    nearest_d: np.ndarray
    _base_xy: np.ndarray | None = None
    _no_margin: np.ndarray | None = None
    deployed_nodes: Callable[[], tuple[np.ndarray, np.ndarray]]
    _nodes_changed: Callable[[], None]

    def _view(self, step: StepInput, current: np.ndarray) -> AgentView:
        """What the agents know this step (:class:`~amronet.algorithms.agent_assisted.drops.AgentView`)."""
        sw, agents, rule = self.swarm, self.agents, self.drop_rule
        is_ref, ref_xy = self.deployed_nodes()
        relay_xy = np.concatenate([ref_xy, sw.xy[sw.state == State.DROPPED]]) if self.settle_at else ref_xy
        contact = None
        if rule.needs_contact or self.reverse_after_s is not None:
            contact = agents_connected(step.table, agents, self.bases, sw.relaying)
        best = self._no_margins() if rule.reads_positions else best_reference_margin(step.table, agents, is_ref)
        if self._base_xy is None:  # (base nodes never move: kept, read-only)
            self._base_xy = sw.xy[self.bases]
            self._base_xy.flags.writeable = False
        # by position, in the order of the fields (keywords cost more, once per step an agent acts)
        return AgentView(step.t, current, self.nearest_d, best, sw.xy[agents], sw.heading[agents], relay_xy,
                         self._base_xy, contact,
                         step.readings.of(agents, self.agent_model) if rule.needs_scans else None,
                         (self.left[agents] >= 1) & (self.pending_until <= step.t))

    def _no_margins(self) -> np.ndarray:
        """What a rule that reads positions is shown of the link margins: ``-inf`` per agent (kept, read-only)."""
        if self._no_margin is None:
            self._no_margin = np.full(len(self.agents), -np.inf)
            self._no_margin.flags.writeable = False
        return self._no_margin

    def _toward(self, m: int, view: AgentView) -> int:
        """The node agent ``m`` puts a router down next to or turns back to (-1: none).

        Its current reference, or when it hears none, the nearest known relay.
        """
        if view.current[m] >= 0:
            return int(view.current[m])
        deployed = np.flatnonzero(self.deployed_nodes()[0])
        if len(deployed) == 0:
            return -1
        d = np.linalg.norm(self.swarm.xy[deployed] - view.xy[m], axis=1)
        return int(deployed[np.argmin(d)])

    def _settle_dropped(self, t: float) -> None:
        """Routers whose settling time is over start to relay and serve as references."""
        ready = [i for i, at in self.settle_at.items() if at <= t]
        if ready:
            self.swarm.state[ready] = State.REFERENCE
            for i in ready:
                del self.settle_at[i]
                if self.strips is not None:
                    self.strips.settled(i)
            self._nodes_changed()

    def _reverse_drops(self, view: AgentView, drop: np.ndarray) -> np.ndarray:
        """Agents backing up that are in contact again drop there (MARBLE's reverse drop)."""
        assert view.in_contact is not None
        return drop | (self.reversing & view.in_contact & view.can_drop)

    def _back_up(self, view: AgentView | None) -> None:
        """MARBLE's reverse drop: an agent out of contact for ``reverse_after_s`` backs up along its own path."""
        assert view is not None and view.in_contact is not None
        self._back_up_at(view.t, view.in_contact)

    def _back_up_at(self, t: float, contact: np.ndarray) -> None:
        """:meth:`_back_up` at time ``t``, ``contact``: which agents have a path to a base station ``(A,)``."""
        assert self.trails is not None
        sw, agents = self.swarm, self.agents
        self.contact_since[contact] = t
        self.reversing &= ~contact
        self.trails.update(sw.xy[agents], ~self.reversing)
        start = ~contact & ~self.reversing & (t - self.contact_since > self.reverse_after_s)
        self.reversing |= start & (self.left[agents] >= 1)
        for m in np.flatnonzero(self.reversing):
            target = self.trails.back(int(m), sw.xy[agents[m]])
            if target is None:  # back at the start of its path and still cut off: give up backing
                self.reversing[m] = False
                self.contact_since[m] = t
                continue
            d = target - sw.xy[agents[m]]
            sw.heading[agents[m]] = np.arctan2(d[1], d[0])
