"""The routers of a drop rule that drives them on to a goal point (``strip-goals``): who drives where, and how it ended.

Agent-assisted deployment puts a router down by its drop rule; under a rule with ``drives_to_goal``
(:mod:`amronet.algorithms.agent_assisted.drops.strip_goals`) the router then drives to the goal the rule picks, with the
controller's goal steering (:class:`~amronet.algorithms.common.goto.GoalSteering`), in state ``strip``.
:class:`StripDrivers`
keeps that bookkeeping for the controller: the goals handed out (a goal stays taken after its router arrived or
gave up on it), the routers still settling that leave once they relay, the goals each router gave up on, and the
counts of the mission report (``reached``, ``stopped_short``, ``no_goal``). A router whose way ends, at its goal or
blocked, serves as a reference; one blocked before its goal tries the rule's next free goal, ``retries`` times.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from amronet.algorithms.agent_assisted.drops.base import DropRule
from amronet.algorithms.common.goto import GoalSteering
from amronet.engine.robots import Role, State, Swarm

__all__ = ["StripDrivers"]


class StripDrivers:
    """The routers on their way to their goal points.

    Args:
        rule: The drop rule (it picks the goals: :meth:`DropRule.goal`).
        swarm: The robots.
        steering: The controller's goal steering (shared with its triangle routers).
        bases: Indices of the base nodes (a router's goal lattice is anchored at its base station).
        changed: Called when routers start or stop serving as references (the controller's cache of deployed nodes).

    Attributes:
        moving: How many routers are on their way.
        goal: Router → the goal it was last sent to.
        waiting: Routers still settling that leave for a goal once they relay → the reference they were put down
            next to.
        counts: ``reached``, ``stopped_short`` (blocked, or no free goal after giving one up), ``no_goal`` (none free
            when put down).
    """

    def __init__(self, rule: DropRule, swarm: Swarm, steering: GoalSteering, bases: np.ndarray,
                 changed: Callable[[], None]) -> None:
        self.rule = rule
        self.swarm = swarm
        self.steering = steering
        self.bases = bases
        self.changed = changed
        self.moving = 0
        self.goal: dict[int, np.ndarray] = {}
        self.taken: list[np.ndarray] = []
        """Every goal a router was sent to (it stays taken after the router arrives or gives up on it)."""
        self.waiting: dict[int, int] = {}
        self.counts = {"reached": 0, "stopped_short": 0, "no_goal": 0}
        self.tries: dict[int, int] = {}
        """Goals each router gave up on."""

    def start(self, router: int, toward: int, retry: bool = False) -> None:
        """Send a router put down next to ``toward`` to its goal (the rule's), or leave it where it is.

        ``retry``: it gave up on its last goal; this is the next.
        """
        sw = self.swarm
        mine = self.bases[sw.status[self.bases] == sw.status[router]]
        origin = sw.xy[mine[0]] if len(mine) else sw.xy[toward]
        nodes = np.flatnonzero(sw.role != Role.AGENT)
        taken = sw.xy[nodes[nodes != router]]
        if self.taken:
            taken = np.concatenate([taken, np.array(self.taken)])
        goal = self.rule.goal(sw.xy[router], sw.xy[toward], origin, taken)
        if goal is None:
            self.counts["stopped_short" if retry else "no_goal"] += 1
            sw.state[router] = State.REFERENCE
            return
        sw.state[router] = State.STRIP
        self.goal[router] = goal
        self.taken.append(goal)
        self.steering.start(np.array([router]), goal[None], np.array([[toward, -1]]))
        self.moving += 1
        self.changed()

    def settled(self, router: int) -> None:
        """A router put down earlier has settled: if it waits to leave for a goal, it leaves now."""
        if router in self.waiting:
            self.start(router, self.waiting.pop(router))

    def drive(self, moving: np.ndarray, scans: np.ndarray, sensor_range: float, max_step: np.ndarray) -> np.ndarray:
        """One steering step of the routers ``moving`` (on their way, sensed this step); the lengths they move.

        Those whose way ends (arrived, or blocked: another goal, or they stay) serve as references again.
        """
        sw = self.swarm
        length, done = self.steering.steer(moving, sw.xy, sw.heading, scans, sensor_range, max_step,
                                           self.rule.keep_radius())
        if done.any():
            ended = moving[done]
            arrived = np.hypot(*(sw.xy[ended] - self.steering.goal[ended]).T) <= 1e-6
            self.counts["reached"] += int(np.count_nonzero(arrived))
            sw.state[ended] = State.REFERENCE
            self.moving -= len(ended)
            self.changed()
            for i in ended[~arrived]:
                self.tries[i] = self.tries.get(i, 0) + 1
                if self.tries[i] > self.rule.retries():
                    self.counts["stopped_short"] += 1
                else:  # the goal stays taken (it is in or behind a wall): the next free one, from here
                    self.start(int(i), int(self.steering.anchors[i, 0]), retry=True)
        return length
