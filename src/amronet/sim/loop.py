"""The simulation loop: one step order, seeded randomness, stop conditions, recording — for one run or many.

The life of a step, in this order and nowhere else (:meth:`Loop.step`):

0. **faults** — nodes whose failure is due (scenario ``faults``, :mod:`amronet.sim.faults`) fail: they stop sending
   and relaying and the table loses their links at once (only in runs with faults);
1. **sense**  — the range rings of every moving robot are ray-cast against the map and the other robots (skipped
   when the controller reads no range readings);
2. **decide** — the algorithm's controller reads those readings and the radio medium's neighbour table, and
   updates states, statuses and headings;
3. **move**   — robots drive along their headings; every move is checked along its whole path;
4. **radio**  — the medium rebuilds the neighbour table once, for everybody, from the new positions;
5. **metrics** — after every step, whether agents are connected; every ``record_every`` steps (and when a run
   settles or hits its time limit) coverage, connected coverage, deployed routers and components; then the
   stop conditions: all routers settled or the coverage target reached (*terminated*), or the time limit
   (*truncated*) (:meth:`Loop.execute`; the runs of a batch are recorded together, :func:`~amronet.sim.run.metrics_of`).

Where the algorithm offers a fast step for the loop's rules (:meth:`~amronet.algorithms.base.Controller.fast_step`,
the stepping protocol of :mod:`amronet.algorithms.stepping`), phases 1–3 run as its compiled passes, which call the
same per-robot functions in the same order: the same result, bit for bit, as the phases one by one
(``step="reference"``, :mod:`amronet.algorithms.phases`). Between two records the fast step may take a stretch of
steps in one call; only the loop advances the clock, the neighbour table and the runs' books, before and after.

A :class:`Loop` holds ``G`` runs of one scenario in one set of arrays: their robots block by block, one neighbour
table that never links robots of different runs, one controller, and every random draw split by run
(:class:`~amronet.engine.streams.RunStreams`). A single run is the loop with ``G = 1``
(:class:`~amronet.sim.simulation.Simulation`); a batch is the same loop with more runs
(:class:`~amronet.sim.batch.BatchSimulation`). Each run's books — rows, stop reason, metrics — are a
:class:`~amronet.sim.run.Run`. All randomness of a run comes from one
``numpy.random.Generator`` seeded by its seed: the same scenario and seed give the same result, bit for bit,
alone or in a batch.
"""

from __future__ import annotations

import itertools
import time
from collections.abc import Callable, Sequence
from typing import TYPE_CHECKING, Literal

import numpy as np

from amronet.algorithms import ALGORITHMS, AreaKnowledge, Command, Controller, Readings, RouterStock, Setup, StepInput
from amronet.algorithms.phases import move, sense
from amronet.algorithms.stepping import AgentBooks, FastStep, StepContext, Watch
from amronet.engine.motion import path_clear
from amronet.engine.radio import NeighbourTable
from amronet.engine.robots import Role, State, Swarm
from amronet.engine.streams import RunStreams
from amronet.errors import ScenarioError
from amronet.scenario import Scenario
from amronet.sim.assemble import (
    World,
    build_medium,
    build_swarm,
    build_world,
    load_scenario_map,
    load_scenario_paths,
    medium_needs_rng,
    robot_model,
)
from amronet.sim.guard import check_scenario, check_world
from amronet.sim.results import RunResult
from amronet.sim.run import Metrics, Run, metrics_of
from amronet.world.occupancy import OccupancyMap
from amronet.world.trajectories import AgentPaths

if TYPE_CHECKING:
    from amronet.outputs.recording import Recorder

__all__ = ["Loop", "Metrics", "StepKind", "check_seed", "move", "sense"]

StepKind = Literal["compiled", "reference"]
"""How a loop steps: ``compiled`` where the algorithm has a compiled step, else (and always with ``reference``) phase
by phase."""


def check_seed(seed: object) -> int:
    """The seed as an ``int``; :class:`ScenarioError` unless it is an integer in ``[0, 2**63 - 1]``."""
    if isinstance(seed, bool) or not isinstance(seed, int | np.integer) or not 0 <= seed < 2**63:
        raise ScenarioError("seed", f"{seed!r} is not an integer in [0, 2**63 - 1]; give e.g. --seed 1")
    return int(seed)


class Loop:
    """Runs of one scenario, one per seed, stepped together in one set of arrays through one step order.

    Args:
        scenario: The validated scenario.
        seeds: One seed per run.
        omap: Use this map instead of loading the scenario's (for generated or scaled maps).
        force: Run even what the resource guard (:mod:`amronet.sim.guard`) calls absurdly long: more than
            ``amronet.limits.MAX_STEPS`` steps or ``MAX_ROBOT_STEPS`` robot-steps (``--force`` on the command line).
        step: ``compiled`` (the default): sense, decide and move run as the algorithm's compiled passes where it has
            them (:meth:`~amronet.algorithms.base.Controller.fast_step`); ``reference``: always the phases one by one,
            through the controller's Python code. Both give the same result bit for bit.

    Raises:
        ScenarioError: A seed is invalid, the scenario cannot be set up (see the scenario's fields), or the resource
            guard refuses it (bodies that cannot fit, memory that is not there, absurd work without ``force``),
            before anything is allocated.
    """

    def __init__(self, scenario: Scenario, seeds: Sequence[int], omap: OccupancyMap | None = None, *,
                 force: bool = False, step: StepKind = "compiled") -> None:
        if step not in ("compiled", "reference"):
            raise ValueError(f"step must be 'compiled' or 'reference', got {step!r}")
        if len(seeds) == 0:
            raise ScenarioError("seeds", "a batch needs at least one seed")
        seeds = [check_seed(s) for s in seeds]
        sc = self.scenario = scenario
        self.dt = sc.sim.dt
        params = sc.algorithm_params()
        controller_cls = ALGORITHMS.lookup(sc.algorithm.name, "algorithm.name")
        r_start = controller_cls.start_range(params, sc.radio.r_c)
        check_scenario(sc, runs=len(seeds), r_start=r_start, force=force)
        omap = omap if omap is not None else load_scenario_map(sc)
        check_world(sc, omap, runs=len(seeds), r_start=r_start)
        self.world: World = build_world(sc, omap)
        self.paths: AgentPaths | None = load_scenario_paths(sc, self.world)
        rngs = [np.random.default_rng(seed) for seed in seeds]
        if len(seeds) > 1 and medium_needs_rng(sc):
            raise ScenarioError("radio", "runs whose radio draws random numbers (shadowing, packet loss) cannot share "
                                "one loop; run them one by one")
        if len(seeds) > 1 and sc.faults:
            raise ScenarioError("faults", "runs with faults cannot share one loop; run them one by one")
        self.medium = build_medium(sc, self.world.omap, rngs[0] if len(seeds) == 1 else None)
        swarms = [build_swarm(sc, self.world, rng, r_start=r_start) for rng in rngs]
        if len(seeds) == 1:
            self.swarm, self.groups, blocks, rng = swarms[0], None, [slice(None)], rngs[0]
        else:
            sizes = [len(s) for s in swarms]
            starts = np.concatenate([[0], np.cumsum(sizes)]).astype(np.int64)
            blocks = [slice(int(a), int(b)) for a, b in itertools.pairwise(starts)]
            self.groups = np.repeat(np.arange(len(seeds), dtype=np.int64), sizes)
            self.swarm = Swarm.concat(swarms)
            rng = RunStreams(rngs, starts)
        self.controller: Controller = controller_cls(params, self._setup(rng))
        self.table: NeighbourTable = self.medium.update(self.swarm.xy, self.groups)
        self.steps = 0
        self._places_robots = sc.agents.per_base > 0 and self.groups is None
        """Whether the controller may put robots down in the decide phase (agents releasing routers; never batched)."""
        self.compiled: FastStep | None = self.controller.fast_step(self.step_context()) if step == "compiled" else None
        """The algorithm's fast sense-decide-move for this loop, or ``None`` (the phases one by one)."""
        self.phase_seconds = ({"sense+decide+move": 0.0, "radio": 0.0} if self.compiled is not None
                              else {"sense": 0.0, "decide": 0.0, "move": 0.0, "radio": 0.0})
        """Wall time spent in each phase (a fast step's three phases are one; a stretch's steps, radio included, count
        there too)."""
        target = sc.sim.coverage_target
        if target is None:  # a replayed mission (agents.trajectories) runs to the end of its paths
            target = None if self.paths is not None else controller_cls.default_coverage_target
        elif target == "off":
            target = None
        self.runs = [Run(self, g, seed, rngs[g], blocks[g], target) for g, seed in enumerate(seeds)]
        self._with_agents = [run for run in self.runs if len(run.agents)]
        self._faulty = self.runs[0] if sc.faults else None
        """The run whose nodes may fail (faults are never batched), or ``None``."""
        self._failed = False  # a node has failed: the table silences it from then on (a stretch would not)
        settled = self._settled_runs()
        for run, now in zip(self.runs, settled, strict=True):
            run.settled_at = 0.0 if now else None

    def step_context(self) -> StepContext:
        """What an algorithm's fast step is told of this loop (:mod:`amronet.algorithms.stepping`)."""
        sc, sw = self.scenario, self.swarm
        return StepContext(omap=self.world.omap, swarm=sw, groups=self.groups, dt=self.dt, faults=bool(sc.faults),
                           collisions=sc.sim.robot_collisions, radio_reach=float(self.medium.reach),
                           agents=sc.agents.per_base > 0 or bool((sw.role == Role.AGENT).any()),
                           keeps_every_pair=self.medium.keeps_every_pair, link_inputs=self.medium.stretch_inputs)

    def _now(self) -> StepInput:
        """The input of the step about to be taken (no readings: a fast step senses itself)."""
        return StepInput(self.steps, self.t, self.dt, self.table, Readings({}))

    def _setup(self, rng: np.random.Generator | RunStreams) -> Setup:
        """What the controller is given: the robots and what the algorithm may know, never the map or scenario."""
        sc, omap = self.scenario, self.world.omap
        stock = None
        if sc.agents.per_base > 0:
            stock = RouterStock(robot=robot_model(sc.routers.robot, "routers.robot"),
                                per_agent=sc.agents.routers_carried,
                                path_clear=lambda start, end, radius: path_clear(omap, start, end, radius),
                                when_empty=sc.agents.when_empty, settle_s=sc.agents.drop_settle_s,
                                reverse_after_s=sc.agents.reverse_drop)
        area = AreaKnowledge(extent=omap.extent,
                             free_area_m2=float(np.count_nonzero(omap.free)) * (omap.resolution**2))
        return Setup(robots=self.swarm, r_c=sc.radio.r_c, dt=self.dt, rng=rng, area=area, stock=stock,
                     paths=self.paths, links_by_distance=self.medium.keeps_every_pair)

    @property
    def t(self) -> float:
        """Simulated time in seconds."""
        return self.steps * self.dt

    # -- the step --------------------------------------------------------------------------------------------
    def step(self) -> None:
        """Advance every run by one step: faults → sense → decide → move → radio, then the agents' connection."""
        sw = self.swarm
        clock = time.perf_counter
        if self._faulty is not None:
            self._fail_nodes(self._faulty)
        if self.compiled is not None:
            t0 = clock()
            self.compiled.step(self._now())
            self.phase_seconds["sense+decide+move"] += clock() - t0
            self.after_compiled_step()
            return
        t0 = clock()
        readings = sense(self.controller, sw, self.world.omap, self.table)
        t1 = clock()
        before = sw.xy.copy() if self._places_robots else None
        command = self.controller.decide(StepInput(self.steps, self.t, self.dt, self.table, readings))
        t2 = clock()
        # a robot put down in the decide phase (a released router) is not where the table has it: the move phase
        # then searches the bodies afresh, so nobody drives into a router released this step
        bodies_table = self.table if before is None or np.array_equal(before, sw.xy) else None
        if self._faulty is not None:  # a failed robot moves no more, whatever its controller asks
            command = Command(command.movers, np.where(sw.state[command.movers] == State.FAILED, 0.0, command.speed))
        move(self.controller, command, sw, self.world.omap, bodies_table, self.dt, self.scenario.sim.robot_collisions)
        t3 = clock()
        self.table = self.medium.update(sw.xy, self.groups, self._silent())
        t4 = clock()
        self._close_step()
        for name, dt in (("sense", t1 - t0), ("decide", t2 - t1), ("move", t3 - t2), ("radio", t4 - t3)):
            self.phase_seconds[name] += dt

    def _stretch(self, fast: FastStep, limit: int, active: np.ndarray, settled: np.ndarray) -> int:
        """Offer ``fast`` a stretch of up to ``limit`` steps; advance the clock, the table and the books by what it did.

        Returns how many steps were taken (0: none could be; the loop then takes the next step itself). Raises
        ``ValueError`` where a robot's position became non-finite (what the radio's table refuses).
        """
        run = self.runs[0]
        restoring, book = 0, run.fault_book
        if book is not None:  # faults (a stretch fails nobody: no fault due in it; the books: Watch.restoring)
            limit, restoring = book.stretch_terms(run, self.steps, limit, self._failed, fast.silences, fast.restores)
            if limit <= 0:
                return 0
        books = None
        if self.groups is None and len(run.agents):  # the agents' books, kept by the stretch step by step
            *arrays, counts, sums = run.connection_books()
            books = AgentBooks(run.bases, run.relay_mask,
                               (np.empty(len(run.agents), dtype=np.bool_), *arrays, counts, sums))
        t0 = time.perf_counter()
        silent = self._silent()
        done = fast.stretch(limit, self._now(), Watch(active, settled, books, silent, restoring))
        if done is None:
            return 0
        if books is not None:
            run.close_connection_books(counts, sums)
        self.steps += done.steps
        if done.non_finite:
            raise ValueError("xy has non-finite coordinates")
        if done.csr is not None:
            self.table = self.medium.plain_table(self.swarm.xy.copy(), *done.csr, self.groups, done.margin, silent)
        if done.finish is not None:
            done.finish(self._now())
        self.phase_seconds["sense+decide+move"] += time.perf_counter() - t0
        if done.finish is None:
            if restoring:  # (the stretch's other steps repaired nothing: Watch.restoring)
                book.observe(run)
            return done.steps
        self.after_compiled_step()
        return done.steps + 1

    def advance(self, steps: int) -> None:
        """Take ``steps`` steps with nothing recorded between them, as :meth:`execute` takes those between two records.

        In stretches where the fast step can take them (:meth:`_stretch`: the same robots and table bit for bit as
        :meth:`step` called ``steps`` times), else one by one. Like :meth:`step`, it keeps no records and stops no run.
        """
        fast = self.compiled if self.compiled is not None and self.compiled.stretches else None
        ids, end = np.arange(len(self.runs), dtype=np.int64), self.steps + steps
        while self.steps < end:
            if fast is None or not self._stretch(fast, end - self.steps, ids, self._settled_runs()):
                self.step()

    def after_compiled_step(self) -> None:
        """The end of a compiled step, once the robots have moved: the radio's table, then the agents' connection."""
        t3 = time.perf_counter()
        self.table = self.medium.update(self.swarm.xy, self.groups, self._silent())
        self.phase_seconds["radio"] += time.perf_counter() - t3
        self._close_step()

    def _close_step(self) -> None:
        """The step is taken: the clock moves on, then the agents' connection and the faults' books."""
        self.steps += 1
        for run in self._with_agents:
            run.observe_agents()
        if self._faulty is not None:
            assert self._faulty.fault_book is not None
            self._faulty.fault_book.observe(self._faulty)

    def _silent(self) -> np.ndarray | None:
        """Nodes that send nothing (failed ones), or ``None`` when none has failed."""
        return self.swarm.state == State.FAILED if self._failed else None

    def _fail_nodes(self, run: Run) -> None:
        """The faults phase (cold: it acts only in a fault's step): nodes due fail, the table loses their links."""
        assert run.faults is not None and run.fault_book is not None
        if not run.faults.pending(self.t):  # (most steps: nothing due, nothing drawn)
            return
        sw = self.swarm
        for kind, ids in run.faults.due(self.t, sw.role, sw.state, sw.deployed):
            self._failed = self._failed or len(ids) > 0
            run.fault_book.before(run, self.t, kind, ids)
            sw.state[ids] = State.FAILED
            self.table = self.medium.update(sw.xy, self.groups, self._silent())
            run.fault_book.after(run)

    def _settled_runs(self) -> np.ndarray:
        """Per run: no robot of it will move again."""
        if self.groups is None:
            return np.array([self.controller.settled])
        unsettled = self.controller.unsettled()
        return np.bincount(self.groups[unsettled], minlength=len(self.runs)) == 0

    # -- the runs --------------------------------------------------------------------------------------------
    def execute(self, progress: Callable[[float, float], None] | None = None,
                recorders: Sequence[Recorder | None] | None = None,
                on_result: Callable[[int, RunResult], None] | None = None) -> list[RunResult]:
        """Step until every run's stop condition holds; one :class:`~amronet.sim.results.RunResult` per run.

        The coverage target is checked at recorded steps (every ``record_every`` steps, and when a run settles or
        reaches the time limit); settling and the time limit after every step. A run that reaches its target or
        settles *terminates*; one that hits the time limit first is *truncated*. A run that stops leaves the books
        at once; its robots stay in the arrays until the loop ends. A run's ``wall_time_s`` is its share of the
        loop's wall time until it stopped. A :class:`~amronet.outputs.recording.Recorder` given for a run is
        shown that run in the metrics phase of every step and ends up in its result. ``on_result(k, result)`` is
        called as run ``k`` (its index) stops, while the others go on (a sweep stores it at once).
        """
        sim = self.scenario.sim
        recorders = list(recorders) if recorders is not None else [None] * len(self.runs)
        start = time.perf_counter()
        results: list[RunResult | None] = [None] * len(self.runs)

        def finish(run: Run, reason: str, final: Metrics) -> None:
            run.end(reason)  # (the metrics just recorded are the final ones: nothing has moved since)
            wall = (time.perf_counter() - start) / len(self.runs)
            results[run.index] = RunResult.from_run(run, final, wall_time_s=wall, recorder=recorders[run.index])
            if on_result is not None:
                on_result(run.index, results[run.index])

        active = []
        for run, m in zip(self.runs, metrics_of(self.runs), strict=True):
            reached = run.record(m)
            if recorders[run.index] is not None:
                recorders[run.index].observe(run)
            if reached:
                finish(run, "coverage_target", m)
            else:
                active.append(run)
        max_steps = round(sim.time_limit / self.dt)
        unrecorded = all(r is None for r in recorders)
        fast = (self.compiled if unrecorded and self.compiled is not None and self.compiled.stretches
                else None)  # (with faults, only the steps before the first: _stretch)
        ids = np.array([run.index for run in active], dtype=np.int64)  # of the active runs
        unsettled = False  # every active run's books say "not settled" (the last step left them so)
        now_settled = self._settled_runs()
        while active:
            # the steps up to the next recorded one (included) in one go where the compiled step can: a stretch stops
            # after a step that changed an active run's settled state, so the books below are what each step leaves
            ahead = min(sim.record_every - self.steps % sim.record_every, max_steps - self.steps)
            if fast is None or ahead <= 0 or not self._stretch(fast, ahead, ids, now_settled):
                self.step()
            now_settled = self._settled_runs()
            at_limit = self.steps >= max_steps
            on_record = self.steps % sim.record_every == 0 or at_limit
            if unrecorded and not on_record and not now_settled[ids].any():  # nothing to record, nobody stops
                if not unsettled:
                    for run in active:
                        run.settle(False)
                    unsettled = True
                continue
            unsettled = False
            recording = active if on_record else [
                run for run in active if sim.stop_when_settled and now_settled[run.index]]
            metrics = dict(zip((run.index for run in recording), metrics_of(recording), strict=True))
            still = []
            for run in active:
                run.settle(bool(now_settled[run.index]))
                settled = sim.stop_when_settled and bool(now_settled[run.index])
                reached = False
                if on_record or settled:
                    reached = run.record(metrics[run.index])
                    if progress is not None:
                        progress(self.t, sim.time_limit)
                reason = "coverage_target" if reached else "settled" if settled else "time_limit" if at_limit else None
                if reason is not None:
                    run.stop_reason = reason
                if recorders[run.index] is not None:
                    recorders[run.index].observe(run)
                if reason is None:
                    still.append(run)
                else:
                    finish(run, reason, metrics[run.index])
            if len(still) < len(active):
                ids = np.array([run.index for run in still], dtype=np.int64)
            active = still
        return [r for r in results if r is not None]
