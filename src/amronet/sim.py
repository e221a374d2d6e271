"""The simulation loop: one step order, seeded randomness, stop conditions, recording.

The life of a step, in this order and nowhere else:

1. **sense**  — the range rings of every moving robot are ray-cast against the map and the other robots (skipped
   when the controller reads no range readings);
2. **decide** — the algorithm's controller reads those readings and the radio medium's neighbour table, and
   updates states, statuses and headings;
3. **move**   — robots drive along their headings; every move is checked along its whole path;
4. **radio**  — the medium rebuilds the neighbour table once, for everybody, from the new positions;
5. **metrics** — every ``record_every`` steps: coverage, connected coverage, deployed routers, components; then
   the stop conditions: all routers settled or the coverage target reached (*terminated*), or the time limit
   (*truncated*).

All randomness comes from one ``numpy.random.Generator`` seeded by the run's seed: the same scenario and seed
give the same positions, bit for bit.

The phases are the functions :func:`sense` and :func:`move` and the medium's ``update``; :class:`Simulation`
runs them for one run, :class:`~amronet.batch.BatchSimulation` for many runs of one scenario in one set of
arrays, in the same order.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np

from amronet.algorithms import ALGORITHMS, Command, Controller, Readings, StepInput
from amronet.assemble import World, build_swarm, build_world
from amronet.errors import ScenarioError
from amronet.motion import drive
from amronet.network import agents_connected, components, connected_to
from amronet.radio import NeighbourTable, make_medium
from amronet.robots import MOBILE_STATES, STATE_NAMES, Kind, Swarm
from amronet.scenario import Scenario
from amronet.sensing import range_scan
from amronet.world.occupancy import OccupancyMap

if TYPE_CHECKING:
    from amronet.recording import Recorder
    from amronet.results import RunResult

__all__ = ["Metrics", "Simulation", "move", "sense"]

def sense(controller: Controller, sw: Swarm, omap: OccupancyMap, table: NeighbourTable) -> Readings:
    """The sense phase: the range rings of every moving robot (none when the controller reads none)."""
    if not controller.needs_range_readings:
        return Readings({})
    mobile = sw.in_states(MOBILE_STATES)
    groups = {}
    for m, kind in enumerate(sw.models):
        who = np.flatnonzero(mobile & (sw.model == m))
        if len(who):
            scans = range_scan(omap, sw.xy, sw.heading, who, kind.sensor_beams, kind.sensor_range,
                               radius=sw.radius, table=table)
            groups[m] = (who, scans)
    return Readings(groups)


def move(controller: Controller, command: Command, sw: Swarm, omap: OccupancyMap, table: NeighbourTable,
         dt: float, bodies: bool) -> None:
    """The move phase: drive the movers, add up distances and tell the controller which moves were refused."""
    movers = command.movers
    refused, travelled = drive(omap, sw.xy, movers, sw.heading[movers], command.speed * dt, sw.radius,
                               bodies=bodies, table=table)
    sw.distance[movers] += travelled
    controller.after_move(movers, refused)


@dataclass
class Metrics:
    """Network metrics at one instant."""

    coverage: float
    connected_coverage: float
    routers_deployed: int
    components: int


@dataclass
class Simulation:
    """One seeded run of a scenario, stepped by :meth:`step` or run to its end by :meth:`run`.

    Args:
        scenario: The validated scenario.
        seed: Seed of the run's random generator.
        omap: Use this map instead of loading the scenario's (for generated or scaled maps).
    """

    scenario: Scenario
    seed: int
    omap: OccupancyMap | None = None
    world: World = field(init=False)
    swarm: Swarm = field(init=False)
    table: NeighbourTable = field(init=False)
    rng: np.random.Generator = field(init=False)

    def __post_init__(self) -> None:
        sc = self.scenario
        if isinstance(self.seed, bool) or not isinstance(self.seed, int | np.integer) or not 0 <= self.seed < 2**63:
            raise ScenarioError("seed", f"{self.seed!r} is not an integer in [0, 2**63 - 1]; give e.g. --seed 1")
        self.rng = np.random.default_rng(self.seed)
        self.dt = sc.sim.dt
        params = sc.algorithm_params()
        self.world = build_world(sc, self.omap)
        self.medium = make_medium(sc.radio.model, sc.radio.r_c)
        margin = getattr(params, "loss_margin", 0.05)
        self.swarm = build_swarm(sc, self.world, self.rng, r_start=(1.0 - margin) * sc.radio.r_c)
        controller_cls = ALGORITHMS[sc.algorithm.name]
        self.controller = controller_cls(params, self.swarm, self.world.omap, sc.radio.r_c, self.dt, self.rng,
                                         scenario=sc)
        self.table = self.medium.update(self.swarm.xy)
        self.steps = 0
        self.rows: list[tuple[float, float, float, int, int]] = []
        self.stop_reason: str | None = None
        self.bases = np.flatnonzero(self.swarm.kind == Kind.BASE)
        self.agents = np.flatnonzero(self.swarm.kind == Kind.AGENT)
        self.coverage_target = sc.sim.coverage_target
        if self.coverage_target is None:
            self.coverage_target = getattr(self.controller, "default_coverage_target", None)
        self.agents_connected_steps = 0
        self.agents_connected_sum = 0.0
        self.agents_connected_window = self._agents_connected()
        self.agents_connected_min = self.agents_connected_window
        self.phase_seconds = {"sense": 0.0, "decide": 0.0, "move": 0.0, "radio": 0.0}
        self.settled_at: float | None = 0.0 if self.controller.settled else None
        """Start of the final stretch of time in which no router moved (``None`` while one still moves)."""

    @property
    def t(self) -> float:
        """Simulated time in seconds."""
        return self.steps * self.dt

    # -- the step --------------------------------------------------------------------------------------------
    def step(self) -> None:
        """Advance the simulation by one step (sense → decide → move → radio; metrics are up to the caller)."""
        sw = self.swarm
        clock = time.perf_counter
        t0 = clock()
        readings = sense(self.controller, sw, self.world.omap, self.table)
        t1 = clock()
        command = self.controller.decide(StepInput(self.steps, self.t, self.dt, self.table, readings))
        t2 = clock()
        move(self.controller, command, sw, self.world.omap, self.table, self.dt, self.scenario.sim.robot_collisions)
        t3 = clock()
        self.table = self.medium.update(sw.xy)
        t4 = clock()
        self.steps += 1
        if len(self.agents):
            frac = self._agents_connected()
            self.agents_connected_steps += 1
            self.agents_connected_sum += frac
            self.agents_connected_window = min(self.agents_connected_window, frac)
            self.agents_connected_min = min(self.agents_connected_min, frac)
        for name, dt in (("sense", t1 - t0), ("decide", t2 - t1), ("move", t3 - t2), ("radio", t4 - t3)):
            self.phase_seconds[name] += dt

    # -- metrics ---------------------------------------------------------------------------------------------
    def metrics(self, method: str | None = None) -> Metrics:
        """Network metrics now.

        Coverage (Eq. 1) over all routers and base nodes, coverage of those connected to a base, deployed
        routers, and the number of components of the deployed network (base nodes and deployed routers).
        """
        sw = self.swarm
        method = method or self.scenario.sim.coverage_method
        r_c = self.scenario.radio.r_c
        network = sw.kind != Kind.AGENT
        linked = connected_to(self.table, self.bases, network)
        deployed = sw.deployed
        n_comp, _ = components(self.table, deployed)
        coverage = self.world.coverage.fraction(sw.xy[network], r_c, method=method)
        everyone_linked = np.array_equal(linked, network)  # then both are the same area: one computation
        return Metrics(
            coverage=coverage,
            connected_coverage=coverage if everyone_linked else self.world.coverage.fraction(sw.xy[linked], r_c,
                                                                                             method=method),
            routers_deployed=int(np.count_nonzero(deployed & (sw.kind == Kind.ROUTER))),
            components=n_comp,
        )

    def _agents_connected(self) -> float:
        """Fraction of agents with a multi-hop path to a base station through the AMRoNet right now."""
        if len(self.agents) == 0:
            return 1.0
        network = self.swarm.kind != Kind.AGENT
        linked = agents_connected(self.table, self.agents, self.bases, network)
        return np.count_nonzero(linked) / len(linked)  # the mean, exactly, at a tenth of ndarray.mean's cost

    @property
    def agents_connected_fraction(self) -> float | None:
        """Mean over all steps of the fraction of agents connected to a base station (``None`` without agents)."""
        if len(self.agents) == 0:
            return None
        if self.agents_connected_steps == 0:
            return self.agents_connected_window
        return self.agents_connected_sum / self.agents_connected_steps

    def _reached(self, m: Metrics) -> bool:
        return self.coverage_target is not None and m.coverage >= self.coverage_target

    def _record(self) -> Metrics:
        m = self.metrics()
        row = (round(self.t, 9), m.coverage, m.connected_coverage, m.routers_deployed, m.components)
        if len(self.agents):
            # the worst fraction seen at any step since the last record, so that no dip is hidden
            row = (*row, self.agents_connected_window)
            self.agents_connected_window = 1.0
        self.rows.append(row)
        return m

    # -- the run ---------------------------------------------------------------------------------------------
    def run(self, progress: Callable[[float, float], None] | None = None, recorder: Recorder | None = None
            ) -> RunResult:
        """Run until a stop condition holds and return a :class:`~amronet.results.RunResult`.

        The coverage target is checked at recorded steps (every ``record_every`` steps); settling and the time
        limit after every step. A run that reaches its target or settles *terminates*; one that hits the time
        limit first is *truncated*. An optional :class:`~amronet.recording.Recorder` is shown the simulation in
        the metrics phase of every step (it keeps every k-th step and the last) and ends up in the result.
        """
        from amronet.results import RunResult

        sim = self.scenario.sim
        start = time.perf_counter()
        reached = self._reached(self._record())
        if recorder is not None:
            recorder.observe(self)
        max_steps = round(sim.time_limit / self.dt)
        while self.stop_reason is None:
            if reached:
                self.stop_reason = "coverage_target"
                break
            self.step()
            now_settled = self.controller.settled
            if not now_settled:
                self.settled_at = None
            elif self.settled_at is None:
                self.settled_at = self.t
            settled = sim.stop_when_settled and now_settled
            at_limit = self.steps >= max_steps
            if self.steps % sim.record_every == 0 or settled or at_limit:
                reached = self._reached(self._record())
                if progress is not None:
                    progress(self.t, sim.time_limit)
            if reached:
                self.stop_reason = "coverage_target"
            elif settled:
                self.stop_reason = "settled"
            elif at_limit:
                self.stop_reason = "time_limit"
            if recorder is not None:
                recorder.observe(self)
        final = self.metrics(method=sim.coverage_method)
        result = RunResult.from_simulation(self, final, wall_time_s=time.perf_counter() - start)
        result.recorder = recorder
        return result

    @property
    def terminated(self) -> bool:
        """``True`` when the run ended because the task ended (settled or target reached), not by time."""
        return self.stop_reason in ("settled", "coverage_target")

    def state_counts(self) -> dict[str, int]:
        """How many robots are in each state."""
        counts = np.bincount(self.swarm.state, minlength=len(STATE_NAMES))
        return {STATE_NAMES[s]: int(c) for s, c in enumerate(counts) if c}
