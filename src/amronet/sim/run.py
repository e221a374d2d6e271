"""One run's books inside the loop: its seed, its block of robots, its recorded rows, its stop reason.

A :class:`Run` is what the loop keeps per run and what the outputs read (:class:`~amronet.sim.results.RunResult`,
:class:`~amronet.outputs.recording.Recorder`): a run alone and a run inside a batch are the same object; only
the block of the loop's arrays it owns differs (all of them, or one run's rows).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Protocol

import numpy as np

from amronet.engine.network import agents_connected, component_counts, components, connected_to
from amronet.engine.radio import NeighbourTable, RadioMedium
from amronet.engine.robots import STATE_NAMES, Role, State, Swarm
from amronet.sim.faults import FaultBook, FaultSchedule
from amronet.sim.outages import OutageTracker

if TYPE_CHECKING:
    from amronet.algorithms import Controller
    from amronet.scenario import Scenario
    from amronet.sim.assemble import World

__all__ = ["LoopOfRuns", "Metrics", "OutageTracker", "Run", "metrics_of"]


class LoopOfRuns(Protocol):
    """What a run's books read of the loop that steps it (:class:`~amronet.sim.loop.Loop`)."""

    scenario: Scenario
    world: World
    dt: float
    steps: int
    medium: RadioMedium
    swarm: Swarm
    table: NeighbourTable
    controller: Controller

STOP_REASONS = ("coverage_target", "settled", "time_limit")
"""Why a run ends: the first two *terminate* it (the task ended), the last *truncates* it."""


@dataclass
class Metrics:
    """Network metrics at one instant."""

    coverage: float
    connected_coverage: float
    routers_deployed: int
    components: int


class Run:
    """The books of run ``index`` of a :class:`~amronet.sim.loop.Loop`.

    Args:
        loop: The loop that steps the run.
        index: The run's number in the loop.
        seed: The run's seed.
        rng: The run's generator.
        robots: The run's rows of the loop's arrays (``slice(None)`` when the loop holds one run).
        coverage_target: Coverage at which the run ends (``None``: none).
    """

    def __init__(self, loop: LoopOfRuns, index: int, seed: int, rng: np.random.Generator, robots: slice,
                 coverage_target: float | None) -> None:
        self.loop = loop
        self.index = index
        self.seed = seed
        self.rng = rng
        self.robots = robots
        self.coverage_target = coverage_target
        self.scenario: Scenario = loop.scenario
        self.world: World = loop.world
        self.dt = loop.dt
        self.rows: list[tuple] = []
        self.stop_reason: str | None = None
        self.settled_at: float | None = None
        """Start of the final stretch of time in which no router moved (``None`` while one still moves)."""
        self._final: tuple[int, Swarm, NeighbourTable] | None = None
        self._last_coverage: dict[str, tuple[str, np.ndarray, float]] = {}
        """Per kind of coverage (``all``, ``linked``), the last one computed: its method, nodes and value."""
        sw = self.swarm
        self.bases = np.flatnonzero(sw.role == Role.BASE)
        self.agents = np.flatnonzero(sw.role == Role.AGENT)
        self.agents_connected_steps = 0
        self.agents_connected_sum = 0.0
        linked = self._agents_linked()
        self.agent_links: OutageTracker | None = OutageTracker(linked) if len(self.agents) else None
        """Per-agent connection, outages included (``None`` without agents)."""
        self.faults: FaultSchedule | None = None
        self.fault_book: FaultBook | None = None
        if self.scenario.faults:  # spawned after the radio medium's streams: the run's other draws stay the same
            self.faults = FaultSchedule(list(self.scenario.faults), self.bases, self.dt, rng)
            self.fault_book = FaultBook()
        self.agents_connected_window = self._fraction(linked)
        self.agents_connected_min = self.agents_connected_window

    # -- the run's view of the loop ------------------------------------------------------------------------
    @property
    def steps(self) -> int:
        """Steps the run has taken."""
        return self.loop.steps if self._final is None else self._final[0]

    @property
    def t(self) -> float:
        """Simulated time in seconds."""
        return self.steps * self.dt

    @property
    def medium(self) -> RadioMedium:
        """The loop's radio medium (the same for every run of a loop)."""
        return self.loop.medium

    @property
    def swarm(self) -> Swarm:
        """The run's robots (views of the loop's arrays while it runs; its own copy once it has ended)."""
        if self._final is not None:
            return self._final[1]
        sw = self.loop.swarm
        return sw if self.robots == slice(None) else sw.rows(self.robots)

    @property
    def table(self) -> NeighbourTable:
        """The run's neighbour table (its block of the loop's table)."""
        if self._final is not None:
            return self._final[2]
        table = self.loop.table
        return table if self.robots == slice(None) else table.block(self.robots)

    @property
    def relay_mask(self) -> np.ndarray:
        """Nodes that relay: base nodes and routers, less routers put down that do not relay yet, boolean ``(N,)``.

        The AMRoNet as every metric sees it: coverage, paths to a base station, the agents' connection
        (:attr:`~amronet.engine.robots.Swarm.relaying`).
        """
        return self.swarm.relaying

    @property
    def live_bases(self) -> np.ndarray:
        """The base reference nodes that have not failed: the sources of every path to a base station."""
        return self.bases[self.swarm.state[self.bases] != State.FAILED]

    @property
    def controller(self) -> Controller:
        """The loop's controller (it drives every run of the loop)."""
        return self.loop.controller

    def report(self) -> dict[str, object]:
        """The algorithm's own numbers for this run (``Controller.report_run``)."""
        return self.loop.controller.report_run(self.robots)

    def mission_report(self) -> dict[str, object]:
        """The controller's numbers for the summary's ``mission`` section (runs alone in their loop; else none)."""
        return self.loop.controller.mission_report() if self.robots == slice(None) else {}

    @property
    def terminated(self) -> bool:
        """``True`` when the run ended because the task ended (settled or target reached), not by time."""
        return self.stop_reason in ("settled", "coverage_target")

    def state_counts(self) -> dict[str, int]:
        """How many robots are in each state."""
        counts = np.bincount(self.swarm.state, minlength=len(STATE_NAMES))
        return {STATE_NAMES[s]: int(c) for s, c in enumerate(counts) if c}

    # -- metrics -----------------------------------------------------------------------------------------------
    def metrics(self, method: str | None = None) -> Metrics:
        """Network metrics now.

        Coverage (Eq. 1) over all routers and base nodes, coverage of those connected to a base, deployed
        routers, and the number of components of the deployed network (base nodes and deployed routers).
        """
        sw, table = self.swarm, self.table
        method = method or self.scenario.sim.coverage_method
        network = self.relay_mask
        linked = connected_to(table, self.live_bases, network)
        deployed = sw.deployed
        n_comp, _ = components(table, deployed)
        coverage, connected = self._coverages(sw.xy, network, linked, method)
        return Metrics(coverage=coverage, connected_coverage=connected,
                       routers_deployed=int(np.count_nonzero(deployed & (sw.role == Role.ROUTER))), components=n_comp)

    def _coverages(self, xy: np.ndarray, network: np.ndarray, linked: np.ndarray, method: str) -> tuple[float, float]:
        """Coverage of the ``network`` nodes and of the ``linked`` ones, from the run's positions ``xy``.

        A coverage is computed again only when its nodes have changed since it was last computed (most records find
        the same deployed network, and the answer depends on nothing else); when every node is linked both are one.
        """
        coverage = self._coverage("all", xy[network], method)
        if np.array_equal(linked, network):
            return coverage, coverage
        return coverage, self._coverage("linked", xy[linked], method)

    def _coverage(self, kind: str, nodes: np.ndarray, method: str) -> float:
        last = self._last_coverage.get(kind)
        if last is not None and last[0] == method and np.array_equal(last[1], nodes):
            return last[2]
        value = self.medium.coverage(self.world.coverage, nodes, method=method)
        self._last_coverage[kind] = (method, nodes, value)
        return value

    def _agents_linked(self) -> np.ndarray:
        """Which agents have a multi-hop path to a base station through the AMRoNet right now, boolean ``(A,)``."""
        if len(self.agents) == 0:
            return np.zeros(0, dtype=bool)
        # every base node is given: a failed one does not relay (relay_mask), so no path starts from it, the same
        # answer as from live_bases without picking them out every step
        return agents_connected(self.table, self.agents, self.bases, self.relay_mask)

    @staticmethod
    def _fraction(linked: np.ndarray) -> float:
        """Fraction of agents connected (1 without agents)."""
        if len(linked) == 0:
            return 1.0
        return np.count_nonzero(linked) / len(linked)  # the mean, exactly, at a tenth of ndarray.mean's cost

    def observe_agents(self) -> None:
        """Account for the agents' connection after a step (runs with agents only): fractions and outages."""
        linked = self._agents_linked()
        if self.agent_links is not None:
            self.agent_links.observe(linked)
        frac = self._fraction(linked)
        self.agents_connected_steps += 1
        self.agents_connected_sum += frac
        self.agents_connected_window = min(self.agents_connected_window, frac)
        self.agents_connected_min = min(self.agents_connected_min, frac)

    def connection_books(self) -> tuple[np.ndarray, ...]:
        """The books :meth:`observe_agents` keeps, as arrays for a compiled caller to keep them in place.

        Returns:
            ``(connected_steps, outages, longest, current, counts, sums)``: the
            :class:`OutageTracker`'s per-agent arrays themselves, then its and this run's numbers,
            ``counts = [steps, all_connected_steps, outage going on, agents_connected_steps]`` and
            ``sums = [agents_connected_sum, agents_connected_window, agents_connected_min]``; hand the last two
            back to :meth:`close_connection_books`. Runs with agents only.
        """
        links = self.agent_links
        assert links is not None
        steps, all_connected, ongoing = links.counts()
        counts = np.array([steps, all_connected, int(ongoing), self.agents_connected_steps], dtype=np.int64)
        sums = np.array([self.agents_connected_sum, self.agents_connected_window, self.agents_connected_min])
        return (*links.live_arrays(), counts, sums)

    def close_connection_books(self, counts: np.ndarray, sums: np.ndarray) -> None:
        """Take back the numbers of :meth:`connection_books` after the steps a compiled caller observed."""
        links = self.agent_links
        assert links is not None
        links.set_counts(int(counts[0]), int(counts[1]), bool(counts[2]))
        self.agents_connected_steps = int(counts[3])
        self.agents_connected_sum, self.agents_connected_window, self.agents_connected_min = (
            float(sums[0]), float(sums[1]), float(sums[2]))

    @property
    def agents_connected_fraction(self) -> float | None:
        """Mean over all steps of the fraction of agents connected to a base station (``None`` without agents)."""
        if len(self.agents) == 0:
            return None
        if self.agents_connected_steps == 0:
            return self.agents_connected_window
        return self.agents_connected_sum / self.agents_connected_steps

    def record(self, m: Metrics | None = None) -> bool:
        """Append a row of metrics to the time series; whether the coverage target is reached.

        Args:
            m: The run's metrics now, when they are known (:func:`metrics_of`); ``None``: computed here.
        """
        if m is None:
            m = self.metrics()
        row = (round(self.t, 9), m.coverage, m.connected_coverage, m.routers_deployed, m.components)
        if len(self.agents):
            # the worst fraction seen at any step since the last record, so that no dip is hidden
            row = (*row, self.agents_connected_window)
            self.agents_connected_window = 1.0
        self.rows.append(row)
        return self.coverage_target is not None and m.coverage >= self.coverage_target

    def settle(self, now_settled: bool) -> None:
        """Note whether the run's robots are all settled after the step just taken."""
        if not now_settled:
            self.settled_at = None
        elif self.settled_at is None:
            self.settled_at = self.t

    def end(self, reason: str) -> None:
        """End the run: keep its own copy of its robots and table (the loop's arrays may go on moving)."""
        if reason not in STOP_REASONS:
            raise ValueError(f"unknown stop reason {reason!r}")
        self.stop_reason = reason
        sw, table = self.swarm, self.table
        self._final = (self.loop.steps, sw.copy() if self.robots != slice(None) else sw, table)


def metrics_of(runs: Sequence[Run]) -> list[Metrics]:
    """The metrics of runs of one loop now: for each, what :meth:`Run.metrics` gives, with one graph search for all.

    A batch records all its running runs at the same steps; their paths to a base station and their components are
    searched in the loop's whole table at once (no link joins two runs), and only coverage is computed run by run.

    Args:
        runs: Runs of one loop that have not ended.
    """
    if len(runs) == 0:
        return []
    loop = runs[0].loop
    if loop.groups is None:
        return [run.metrics() for run in runs]
    sw, table, groups = loop.swarm, loop.table, loop.groups
    method = loop.scenario.sim.coverage_method
    network = sw.relaying
    bases = np.concatenate([run.bases + run.robots.start for run in runs])
    linked = connected_to(table, bases[sw.state[bases] != State.FAILED], network)
    deployed = sw.deployed
    n_components = component_counts(table, deployed, groups, len(loop.runs))
    routers = np.bincount(groups[deployed & (sw.role == Role.ROUTER)], minlength=len(loop.runs))
    blocks = np.array([(run.robots.start, run.robots.stop) for run in runs], dtype=np.int64)
    fractions = loop.medium.run_coverages(loop.world.coverage, sw.xy, network, linked, blocks, method)
    out = []
    for k, run in enumerate(runs):
        block = run.robots
        if fractions is not None:
            coverage, connected = fractions[k]
        else:
            coverage, connected = run._coverages(sw.xy[block], network[block], linked[block], method)
        out.append(Metrics(coverage=coverage, connected_coverage=connected, routers_deployed=int(routers[run.index]),
                           components=int(n_components[run.index])))
    return out
