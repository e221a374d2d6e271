"""``repair: relocate`` — deployed routers that a failure cut off move to bridge the cut, with local information only.

In the spirit of RIM (Recovery through Inward Motion; Younis, Lee, Gupta, Fisher: *Localized Movement-Assisted
Sensor Deployment* / the survey of Younis, Senturk, Akkaya, Lee, Senel, *Computer Networks* 58 (2014) 254-283):
when a node fails, its neighbours move inward toward its position, and a node that loses its link to a moving
neighbour follows it (cascaded moves). Two changes, so that routers that are still connected never move and the
network does not contract for nothing (DARA's concern with cut vertices):

* **Who moves**: a deployed router that has lost a neighbour — a node it heard at the previous step is gone from
  its row of the neighbour table for ``confirm_s`` seconds (a missed heartbeat, so a link that flickers does not
  count) — *and* has no path to a base station any more (what its routing tells it).
* **Where to**: toward the lost neighbour's last known position (deployed nodes do not move, so that is where it
  was); when the lost neighbour was itself relocating, toward the goal it announced before it left (the cascade).
  Going all the way to the failed node's position puts the router within ``r_c`` of every former neighbour of the
  failed node, which is what bridges the cut.
* **When it stops**: as soon as it has a path to a base station again, or when it has made no progress for
  ``give_up_steps`` steps (the goal sits inside the failed body or a wall); it then serves as a reference again.

While it moves a router relays (it is on the air) but serves as no reference (state ``relocating``). Loss detection
compares this step's links among the deployed routers and base nodes with the previous step's: an event, cold.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from amronet.algorithms.common.goto import GoalSteering
from amronet.engine.network import connected_to
from amronet.engine.radio import NeighbourTable
from amronet.engine.robots import Role, State, Swarm

__all__ = ["Relocator"]

_KEY = np.int64(1 << 31)
"""A link ``i -> j`` is the key ``i * _KEY + j`` (ids stay below 2**31; the swarm grows, so its size cannot be used)."""


@dataclass
class _Loss:
    since: float
    where: np.ndarray


@dataclass
class Relocator:
    """The relocation repair's state (see the module docstring).

    Args:
        n: Number of robots now (grows with :meth:`grow`).
        confirm_s: How long a neighbour must be missing before it counts as lost, seconds.
        give_up_steps: Steps without progress after which a relocating router stops.
    """

    n: int
    confirm_s: float
    give_up_steps: int
    steering: GoalSteering = field(init=False)
    moves: int = 0
    """Relocations started."""
    _pairs: np.ndarray = field(init=False)
    _lost: dict[tuple[int, int], _Loss] = field(init=False, default_factory=dict)

    def __post_init__(self) -> None:
        self.steering = GoalSteering(self.n, n_anchors=1, give_up_steps=self.give_up_steps)
        self._pairs = np.zeros(0, dtype=np.int64)

    def grow(self, n_new: int) -> None:
        """Make room for ``n_new`` robots added at the end (routers released)."""
        self.steering.grow(n_new)
        self.n += n_new

    def _watched(self, sw: Swarm) -> np.ndarray:
        """Base nodes, deployed routers and relocating routers: the nodes whose links are watched."""
        return (sw.role != Role.AGENT) & (sw.deployed | (sw.state == State.RELOCATING))

    def update(self, t: float, table: NeighbourTable, sw: Swarm) -> tuple[np.ndarray, np.ndarray]:
        """Notice lost neighbours and start relocations; which routers start and which stop now.

        Returns:
            ``(started, stopped)``: router ids whose state this call changed (to ``relocating`` and back to
            ``reference``).
        """
        watched = self._watched(sw)
        pairs = table.pairs
        keep = watched[pairs[:, 0]] & watched[pairs[:, 1]] if len(pairs) else np.zeros(0, dtype=bool)
        n = _KEY
        keys = np.concatenate([pairs[keep, 0] * n + pairs[keep, 1], pairs[keep, 1] * n + pairs[keep, 0]])
        keys.sort()
        gone = np.setdiff1d(self._pairs, keys, assume_unique=True)
        if self._lost:  # neighbours heard again: not lost after all
            heard = set(keys.tolist())
            for k in [k for k in self._lost if k[0] * n + k[1] in heard]:
                del self._lost[k]
        for key in gone.tolist():
            i, j = divmod(key, int(_KEY))
            moving = sw.state[j] == State.RELOCATING
            where = self.steering.goal[j].copy() if moving else sw.xy[j].copy()
            self._lost.setdefault((i, j), _Loss(t, where))
        self._pairs = keys
        started = self._start(t, table, sw)
        stopped = self._stop(table, sw)
        return started, stopped

    def _cut_off(self, table: NeighbourTable, sw: Swarm) -> np.ndarray:
        bases = np.flatnonzero(sw.role == Role.BASE)
        return ~connected_to(table, bases, sw.role != Role.AGENT)

    def _start(self, t: float, table: NeighbourTable, sw: Swarm) -> np.ndarray:
        due = [(i, loss) for (i, _), loss in self._lost.items() if t - loss.since >= self.confirm_s - 1e-9]
        if not due:
            return np.zeros(0, dtype=np.int64)
        cut = self._cut_off(table, sw)
        started = []
        for i, loss in due:
            if cut[i] and i not in started and self._movable(i, sw) and not self._waits(i, started, table, sw):
                self._begin(i, loss, sw)
                started.append(i)
        for i in started:
            for key in [k for k in self._lost if k[0] == i]:
                del self._lost[key]
        self.moves += len(started)
        return np.array(started, dtype=np.int64)

    def _movable(self, i: int, sw: Swarm) -> bool:
        """Whether router ``i``, cut off and having lost a neighbour, starts to move: a deployed reference router."""
        return bool(sw.role[i] == Role.ROUTER and sw.state[i] == State.REFERENCE)

    def _waits(self, i: int, started: list[int], table: NeighbourTable, sw: Swarm) -> bool:
        """Whether router ``i``, due to move, waits this step (``started``: those that start this step): never."""
        return False

    def _begin(self, i: int, loss: _Loss, sw: Swarm) -> None:
        """Start router ``i``'s move: toward where its lost neighbour was (or the goal it announced)."""
        self.steering.start(np.array([i]), loss.where[None], np.array([[-1]]))

    def carried(self, router: int, agent: int, sw: Swarm) -> None:
        """An agent has just put ``router`` down (relocation keeps nothing of how it got there)."""

    def steer(self, moving: np.ndarray, sw: Swarm, scans: np.ndarray, sensor_range: float,
              max_step: np.ndarray, r_keep: float) -> tuple[np.ndarray, np.ndarray]:
        """One step of the routers ``moving`` (headings set in place): ``(step_length, done)``; done ones stay."""
        return self.steering.steer(moving, sw.xy, sw.heading, scans, sensor_range, max_step, r_keep)

    def _stop(self, table: NeighbourTable, sw: Swarm) -> np.ndarray:
        moving = np.flatnonzero(sw.state == State.RELOCATING)
        if not len(moving):
            return moving
        return moving[~self._cut_off(table, sw)[moving]]
