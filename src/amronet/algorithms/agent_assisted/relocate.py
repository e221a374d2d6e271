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


def _links(table: NeighbourTable, on: np.ndarray) -> np.ndarray:
    """The table's links among the nodes ``on`` (a mask), both ways, as ascending keys (rows and columns ascend)."""
    indptr = table.indptr
    rows = np.repeat(np.arange(len(indptr) - 1, dtype=np.int64), indptr[1:] - indptr[:-1])
    cols = table.indices
    keep = on[rows] & on[cols]
    keep &= rows != cols  # (as the table's pairs, which leave the diagonal out)
    return rows[keep] * _KEY + cols[keep]


def _member(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Which entries of ``a`` are in ``b`` (ascending, unique)."""
    if not len(b):
        return np.zeros(len(a), dtype=bool)
    return b[np.minimum(np.searchsorted(b, a), len(b) - 1)] == a


def _same(a: np.ndarray | None, b: np.ndarray) -> bool:
    return a is not None and a.shape == b.shape and bool((a == b).all())


@dataclass
class Relocator:
    """The relocation repair's state (see the module docstring).

    Losses are kept as arrays in the order they were noticed (by time, then by link): the router ``_li`` lost
    ``_lj`` at ``_since``, which was at (or headed for) ``_where``. A loss stays until the link is heard again or its
    router starts to move: a loss of a router that is not cut off (or cannot move) now can start a move later.

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
    _li: np.ndarray = field(init=False)
    _lj: np.ndarray = field(init=False)
    _since: np.ndarray = field(init=False)
    _where: np.ndarray = field(init=False)
    _network: np.ndarray = field(init=False)
    """This step's links among the base nodes and routers (what :meth:`_cut_off` depends on)."""
    _cut_links: np.ndarray | None = field(init=False, default=None)
    _cut: np.ndarray = field(init=False)
    """The last cut-off mask and the links it was found from (the same links give the same mask)."""
    _last: tuple[np.ndarray, np.ndarray, np.ndarray] | None = field(init=False, default=None)
    """The last table's links (its ``indptr`` and ``indices``) and the nodes watched then."""

    def __post_init__(self) -> None:
        self.steering = GoalSteering(self.n, n_anchors=1, give_up_steps=self.give_up_steps)
        self._pairs = self._network = np.zeros(0, dtype=np.int64)
        self._li = np.zeros(0, dtype=np.int64)
        self._lj = np.zeros(0, dtype=np.int64)
        self._since = np.zeros(0)
        self._where = np.zeros((0, 2))
        self._cut = np.zeros(0, dtype=bool)

    def grow(self, n_new: int) -> None:
        """Make room for ``n_new`` robots added at the end (routers released)."""
        self.steering.grow(n_new)
        self.n += n_new

    def odometry(self, sw: Swarm) -> None:
        """What :meth:`update` records of the robots' moves before it looks at the links (relocation: nothing)."""

    def update(self, t: float, table: NeighbourTable, sw: Swarm) -> tuple[np.ndarray, np.ndarray]:
        """Notice lost neighbours and start relocations; which routers start and which stop now.

        Loss detection compares this step's links among the watched nodes (base nodes, deployed and relocating
        routers) with the previous step's; when they are the same nothing is lost or heard again. When the table
        holds the same links as the last one (its positions may differ) and the same nodes are watched, so do they.

        Returns:
            ``(started, stopped)``: router ids whose state this call changed (to ``relocating`` and back to
            ``reference``).
        """
        network = sw.role != Role.AGENT
        watched = (sw.deployed | (sw.state == State.RELOCATING)) & network
        last = self._last
        if not (last is not None and _same(last[0], table.indptr) and _same(last[1], table.indices)
                and _same(last[2], watched)):
            self._last = (table.indptr.copy(), table.indices.copy(), watched)
            links = self._network = _links(table, network)
            keys = links if watched[network].all() else links[watched[links // _KEY] & watched[links % _KEY]]
            if not _same(self._pairs, keys):
                self._notice(t, keys, sw)
        started = self._start(t, table, sw)
        stopped = self._stop(table, sw)
        return started, stopped

    def _notice(self, t: float, keys: np.ndarray, sw: Swarm) -> None:
        """Forget the losses whose link is heard again, note the links gone since the last step."""
        if len(self._li):
            heard = _member(self._li * _KEY + self._lj, keys)
            if heard.any():
                self._keep(~heard)
        gone = self._pairs[~_member(self._pairs, keys)]
        if len(gone):
            i, j = gone // _KEY, gone % _KEY
            moving = sw.state[j] == State.RELOCATING
            self._li = np.concatenate([self._li, i])
            self._lj = np.concatenate([self._lj, j])
            self._since = np.concatenate([self._since, np.full(len(gone), t)])
            self._where = np.concatenate([self._where, np.where(moving[:, None], self.steering.goal[j], sw.xy[j])])
        self._pairs = keys

    def _keep(self, keep: np.ndarray) -> None:
        self._li, self._lj, self._since, self._where = (self._li[keep], self._lj[keep], self._since[keep],
                                                        self._where[keep])

    def _cut_off(self, table: NeighbourTable, sw: Swarm) -> np.ndarray:
        """Which nodes have no path to a base station (found again only when the links among the network change)."""
        if not _same(self._cut_links, self._network) or len(self._cut) != len(table.indptr) - 1:
            bases = np.flatnonzero(sw.role == Role.BASE)
            self._cut = ~connected_to(table, bases, sw.role != Role.AGENT)
            self._cut_links = self._network
        return self._cut

    def confirmed(self, t: float | np.ndarray, since: float | np.ndarray) -> bool | np.ndarray:
        """Whether what began at ``since`` has lasted ``confirm_s`` at ``t`` (arrays broadcast).

        A hair of slack (1e-9 s) for the rounding of the steps' times.
        """
        return t - since >= self.confirm_s - 1e-9

    def _due(self, t: float, sw: Swarm) -> np.ndarray | None:
        """Per loss waiting, whether it is due at ``t`` and its router may move; ``None`` where none is."""
        if not len(self._li) or not self.confirmed(t, self._since[0]):  # (oldest first: none is due)
            return None
        due = self.confirmed(t, self._since) & self._movable(self._li, sw)
        return due if due.any() else None

    def _start(self, t: float, table: NeighbourTable, sw: Swarm) -> np.ndarray:
        none = np.zeros(0, dtype=np.int64)
        due = self._due(t, sw)
        if due is None:
            return none
        due &= self._cut_off(table, sw)[self._li]
        if not due.any():
            return none
        chosen = self._choose(np.flatnonzero(due), table, sw)
        if not len(chosen):  # (every router due waits: nothing to start, no loss to forget)
            return none
        started = self._li[chosen]
        self._begin(chosen, sw)
        self._keep(~np.isin(self._li, started))
        self.moves += len(started)
        return started

    def waiting_movable(self, sw: Swarm) -> np.ndarray:
        """Per loss waiting, whether its router may move (:meth:`_movable`)."""
        return self._movable(self._li, sw) if len(self._li) else np.zeros(0, dtype=bool)

    def could_start(self, t: float, table: NeighbourTable, sw: Swarm, cut: np.ndarray | None = None) -> bool:
        """Whether :meth:`update` at ``t`` on ``table`` could start a move.

        Only a loss waiting now can start one (a loss noticed at ``t`` is due ``confirm_s`` later), once it is due, its
        router may move and has no path to a base station on ``table`` (found afresh here, as :meth:`_start` finds it
        after the look, unless the caller found it: ``cut``), and :meth:`_choose` lets it start (a rule's routers may
        wait for one another).
        """
        due = self._due(t, sw)
        if due is None:
            return False
        if cut is None:
            cut = ~connected_to(table, np.flatnonzero(sw.role == Role.BASE), sw.role != Role.AGENT)
        due &= cut[self._li]
        return bool(due.any()) and len(self._choose(np.flatnonzero(due), table, sw)) > 0

    def quiet_steps(self, index: int, dt: float, limit: int, cut: np.ndarray, sw: Swarm) -> int:
        """How many steps from step ``index`` on (at most ``limit``) come before a loss of a cut-off router falls due.

        Only losses whose router may move (:meth:`_movable`) and is cut off (the mask ``cut``) count; the steps' times
        are the loop's (``step * dt``).
        """
        waiting = self.waiting_movable(sw)
        if len(waiting):
            waiting &= cut[self._li]
        if not waiting.any():
            return limit
        t = (index + np.arange(limit, dtype=np.int64)) * dt
        due = self.confirmed(t[:, None], self._since[waiting][None, :]).any(axis=1)
        return int(np.argmax(due)) if due.any() else limit

    def may_start(self, table: NeighbourTable, sw: Swarm) -> bool:
        """Whether a loss waits whose router may move and is cut off: a move may start once it is due."""
        movable = self.waiting_movable(sw)
        return bool(movable.any() and self._cut_off(table, sw)[self._li[movable]].any())

    def _movable(self, routers: np.ndarray, sw: Swarm) -> np.ndarray:
        """Which of ``routers``, cut off and having lost a neighbour, may start to move: deployed reference routers."""
        return (sw.role[routers] == Role.ROUTER) & (sw.state[routers] == State.REFERENCE)

    def _choose(self, due: np.ndarray, table: NeighbourTable, sw: Swarm) -> np.ndarray:
        """Of the due losses ``due`` (indices, in order) of routers that may move, those whose routers start now.

        Every router starts, with its first loss.
        """
        _, first = np.unique(self._li[due], return_index=True)
        return due[np.sort(first)]

    def _begin(self, chosen: np.ndarray, sw: Swarm) -> None:
        """Start the moves of the losses ``chosen``: toward where the lost neighbour was (or the goal it announced)."""
        self.steering.start(self._li[chosen], self._where[chosen], np.full((len(chosen), 1), -1, dtype=np.int64))

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
