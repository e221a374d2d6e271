"""Node failures (scenario ``faults``) and what they cost: which nodes fail when, and the books of the repair.

A failed node stops sending and relaying at once and stays where it is, as an obstacle (state ``failed``): the radio
medium gives it no links, the metrics count it nowhere, and no controller is told. The survivors notice only what
they sense or hear: a reference gone from their row of the neighbour table. Faults are the first phase of a step
(:meth:`amronet.sim.loop.Loop.step`), before sensing, so the step's controllers already hear the network without the
failed nodes.

Randomness: which routers fail (``routers: 0.2``) and the Poisson failures (``rate_per_hour``) are drawn from a
stream spawned from the run's generator when the run starts, after the radio medium's, so a run's own draws (start
positions, random walks) and its shadowing are the same with and without faults.

The books (:class:`FaultBook`), per fault event: the time, the nodes, coverage and connected coverage just before
and just after, and how long until every surviving agent and every deployed router again had a path to a base
station (``restored_after_s``; ``None`` if never within the run). Over the run: nodes failed, routers added after
the first fault (extra routers), and the distance travelled after it by the routers that were deployed then (the
repair's distance) and how many of them moved (its scope).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, Protocol

import numpy as np

from amronet.algorithms.stepping import RESTORING_AGENTS, RESTORING_ROUTERS
from amronet.engine.network import agents_connected, connected_to
from amronet.engine.robots import Role, State

if TYPE_CHECKING:
    from amronet.engine.robots import Swarm
    from amronet.engine.table import NeighbourTable
    from amronet.scenario import FaultSpec

__all__ = ["FaultBook", "FaultSchedule"]


class FaultedRun(Protocol):
    """What the faults' books read of a run (:class:`~amronet.sim.run.Run`)."""

    agents: np.ndarray
    faults: FaultSchedule | None
    live_bases: np.ndarray
    swarm: Swarm
    t: float
    table: NeighbourTable

    def metrics(self, method: str | None = None) -> Any:
        """The run's network metrics now."""



class FaultSchedule:
    """Which nodes of one run fail at which step.

    Args:
        specs: The scenario's ``faults``.
        bases: Node ids of the base reference nodes, in the order of the scenario's base stations.
        dt: Step length, seconds.
        rng: The run's generator (a child stream is spawned from it).
    """

    def __init__(self, specs: list[FaultSpec], bases: np.ndarray, dt: float, rng: np.random.Generator) -> None:
        self.timed = sorted(((float(s.at), k, s) for k, s in enumerate(specs) if s.kind != "rate_per_hour"),
                            key=lambda e: (e[0], e[1]))
        self.poisson = [s for s in specs if s.kind == "rate_per_hour"]
        self.bases = bases
        self.dt = dt
        self.rng = rng.spawn(1)[0]
        self.skipped: list[str] = []
        """Entries that named nodes that could not fail (not there yet, agents, failed already), one line each."""

    @staticmethod
    def _strikes(at: float, t: float) -> bool:
        """Whether an event at ``at`` is due in the step that starts at ``t`` (:meth:`due`'s test)."""
        return at <= t + 1e-9 * max(1.0, t)

    def quiet_steps(self, step: int, limit: int) -> int:
        """Steps from step index ``step`` on (at most ``limit``) in which :meth:`due` would find and draw nothing.

        A timed fault strikes in the first step whose start is at or past its time; a Poisson failure rate draws in
        every step from its ``at`` on. The loop takes such steps in a stretch (:meth:`amronet.sim.loop.Loop.advance`).
        """
        dt = self.dt
        quiet = limit
        for at in self._starts():
            k = max(int(at / dt) - 2, step)  # (then up to the exact step, with due's own arithmetic)
            while k < step + quiet and not self._strikes(at, k * dt):
                k += 1
            quiet = min(quiet, k - step)
        return max(quiet, 0)

    def pending(self, t: float) -> bool:
        """Whether :meth:`due` may find or draw anything in the step that starts at ``t`` (else it returns ``[]``)."""
        return any(self._strikes(at, t) for at in self._starts())

    def _starts(self) -> list[float]:
        """When :meth:`due` may next act: the next timed fault's time, and each Poisson failure rate's start."""
        return [at for at, _, _ in self.timed[:1]] + [float(s.at or 0.0) for s in self.poisson]

    def due(self, t: float, role: np.ndarray, state: np.ndarray, deployed: np.ndarray) -> list[tuple[str, np.ndarray]]:
        """The faults of the step that starts at ``t``: ``(kind, node ids)`` per event, ids sorted.

        Args:
            t: Start time of the step, seconds.
            role: Roles of all nodes.
            state: States of all nodes.
            deployed: Mask of the deployed nodes (base nodes and deployed routers).
        """
        events = []
        alive = state != State.FAILED
        while self.timed and self._strikes(self.timed[0][0], t):
            _, k, spec = self.timed.pop(0)
            if spec.kind == "routers":
                pool = np.flatnonzero(deployed & (role == Role.ROUTER) & alive)
                count = round(spec.routers * len(pool))
                ids = np.sort(self.rng.choice(pool, size=count, replace=False)) if count else pool[:0]
            elif spec.kind == "base_station":
                ids = self.bases[[spec.base_station]]
            else:
                wanted = np.array(spec.ids, dtype=np.int64)
                ok = (wanted < len(role))
                ok[ok] &= (role[wanted[ok]] != Role.AGENT) & alive[wanted[ok]]
                if not ok.all():
                    self.skipped.append(f"faults[{k}]: nodes {wanted[~ok].tolist()} did not exist, were agents or had "
                                        f"failed at t = {t:g} s")
                ids = np.unique(wanted[ok])
            events.append((spec.kind, ids))
            alive[ids] = False
        for spec in self.poisson:
            if not self._strikes(spec.at or 0.0, t):
                continue
            pool = np.flatnonzero(deployed & (role == Role.ROUTER) & alive)
            p = -np.expm1(-spec.rate_per_hour * self.dt / 3600.0)
            hit = pool[self.rng.random(len(pool)) < p]
            if len(hit):
                events.append(("rate_per_hour", hit))
                alive[hit] = False
        return events


@dataclass
class _Event:
    t: float
    kind: str
    nodes: list[int]
    coverage_before: float
    connected_coverage_before: float
    coverage_after: float = float("nan")
    connected_coverage_after: float = float("nan")
    restored_at: float | None = None


@dataclass
class FaultBook:
    """The repair's books of one run (see the module docstring)."""

    events: list[_Event] = field(default_factory=list)
    routers_at_first: int | None = None
    distance_at_first: np.ndarray | None = None
    """Distance travelled so far by each node when the first fault struck (routers deployed then count)."""
    deployed_at_first: np.ndarray | None = None
    _open: int = 0
    """Events whose damage is not repaired yet (those of :attr:`events` with ``restored_at`` ``None``)."""

    def before(self, run: FaultedRun, t: float, kind: str, ids: np.ndarray) -> None:
        """Note the state of the network just before nodes ``ids`` fail."""
        m = run.metrics()
        sw = run.swarm
        if self.routers_at_first is None:
            self.routers_at_first = int(np.count_nonzero(sw.role == Role.ROUTER))
            self.distance_at_first = sw.distance.copy()
            self.deployed_at_first = sw.deployed & (sw.role == Role.ROUTER)
        self.events.append(_Event(t, kind, [int(i) for i in ids], m.coverage, m.connected_coverage))
        self._open += 1

    def after(self, run: FaultedRun) -> None:
        """Note the network just after the last event's nodes failed (the table already without them).

        A fault that cut nobody off (every surviving agent and deployed router still has a path to a base station)
        is restored after 0 s.
        """
        m = run.metrics()
        ev = self.events[-1]
        ev.coverage_after, ev.connected_coverage_after = m.coverage, m.connected_coverage
        if self._all_linked(run):
            ev.restored_at = ev.t
            self._open -= 1

    @property
    def restoring(self) -> bool:
        """Whether some event's damage is not repaired yet."""
        return self._open > 0

    def observe(self, run: FaultedRun) -> None:
        """After a step: whether every surviving agent and deployed router has a path to a base station again."""
        if not self.restoring or not self._all_linked(run):
            return
        for ev in self.events:
            if ev.restored_at is None:
                ev.restored_at = run.t
        self._open = 0

    @classmethod
    def _all_linked(cls, run: FaultedRun) -> bool:
        """Whether every surviving agent and deployed router has a path to a base station that has not failed."""
        if not cls.routers_linked(run):
            return False
        live_bases = run.live_bases
        return not len(run.agents) or bool(
            len(live_bases) and agents_connected(run.table, run.agents, live_bases, run.swarm.relaying).all())

    @staticmethod
    def routers_linked(run: FaultedRun) -> bool:
        """Whether every deployed router has a path to a base station that has not failed.

        A router that a repair moves (state ``relocating``) counts: it was deployed, and its move is over only when
        it has a path again or has given up.
        """
        sw, live_bases = run.swarm, run.live_bases
        routers = (sw.deployed | (sw.state == State.RELOCATING)) & (sw.role == Role.ROUTER)  # moving ones too
        if len(live_bases) == 0:
            return not routers.any()
        return bool(connected_to(run.table, live_bases, sw.relaying)[routers].all())

    def stretch_terms(self, run: FaultedRun, step: int, limit: int, failed: bool, silences: bool, restores: bool
                      ) -> tuple[int, int]:
        """How many steps from ``step`` on a stretch may take, and what it is told of the damage.

        Returns:
            ``(steps, restoring)``: at most ``limit`` steps in which no fault is due (0 where the fast step does not
            silence the nodes that ``failed`` already, or cannot watch a repair that is not over), and
            :attr:`~amronet.algorithms.stepping.Watch.restoring`: what the stretch must do so that the books need
            no step of it but its last (:meth:`observe`).
        """
        waiting = self.restoring
        if (failed and not silences) or (waiting and not restores) or run.faults is None:
            return 0, 0
        restoring = (RESTORING_AGENTS if self.routers_linked(run) else RESTORING_ROUTERS) if waiting else 0
        return run.faults.quiet_steps(step, limit), restoring

    def summary(self, run: FaultedRun, schedule: FaultSchedule | None) -> dict[str, Any]:
        """The ``faults`` section of ``summary.json``."""
        sw = run.swarm
        out: dict[str, Any] = {"nodes_failed": int(np.count_nonzero(sw.state == State.FAILED)), "events": []}
        for ev in self.events:
            out["events"].append({
                "t": round(ev.t, 9), "kind": ev.kind, "nodes": ev.nodes,
                "coverage_before": ev.coverage_before, "coverage_after": ev.coverage_after,
                "connected_coverage_before": ev.connected_coverage_before,
                "connected_coverage_after": ev.connected_coverage_after,
                "restored_after_s": None if ev.restored_at is None else round(ev.restored_at - ev.t, 9)})
        if self.routers_at_first is not None:
            assert self.distance_at_first is not None and self.deployed_at_first is not None
            n0 = len(self.distance_at_first)
            moved = sw.distance[:n0] - self.distance_at_first
            repairing = self.deployed_at_first & (moved > 0)
            out.update(extra_routers=int(np.count_nonzero(sw.role == Role.ROUTER)) - self.routers_at_first,
                       repair_distance_m=float(moved[self.deployed_at_first].sum()),
                       routers_moved=int(np.count_nonzero(repairing)))
        if schedule is not None and schedule.skipped:
            out["skipped"] = list(schedule.skipped)
        return out
