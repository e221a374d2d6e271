"""Many seeded runs of one scenario stepped together in one set of arrays.

A 30-robot step costs about 100 us, nearly all of it the fixed cost of Python and NumPy calls, not the work on
30 robots. :class:`BatchSimulation` steps ``G`` runs of the same scenario as one swarm: their robots are
concatenated block by block, the radio medium builds one neighbour table that never links robots of different
runs (:func:`~amronet.neighbours.neighbour_csr` with groups), one controller decides for all of them, and every
random draw is split by run (:class:`~amronet.streams.RunStreams`). The step order is the one of
:class:`~amronet.sim.Simulation` (sense → decide → move → radio → metrics), through the same phase functions.

Every run gives the same result bit for bit as :meth:`Simulation.run <amronet.sim.Simulation.run>` with its
seed: it starts from the same :class:`~amronet.sim.Simulation` (so the same start positions), no robot of
another run is ever in its neighbour table, its random numbers come from its own generator in its own order,
and its metrics and stop rules are evaluated on its own block. A run that stops is taken out of the books at
once; its robots stay in the arrays (settled runs do not move any more) until the batch ends.

Only controllers that declare :attr:`~amronet.algorithms.base.Controller.batchable` (self-spreading and the
potential field) are batched, and only scenarios without agents; :func:`batchable` says which.
"""

from __future__ import annotations

import time

import numpy as np

from amronet.algorithms import ALGORITHMS, StepInput
from amronet.errors import ScenarioError
from amronet.results import RunResult
from amronet.robots import Swarm
from amronet.scenario import Scenario
from amronet.sim import Simulation, move, sense
from amronet.streams import RunStreams
from amronet.world.occupancy import OccupancyMap

__all__ = ["BatchSimulation", "batchable", "run_seeds"]


def batchable(scenario: Scenario) -> bool:
    """Whether runs of ``scenario`` can be stepped together by :class:`BatchSimulation`."""
    return ALGORITHMS[scenario.algorithm.name].batchable and scenario.agents.per_base == 0


def run_seeds(scenario: Scenario, seeds: list[int]) -> list[RunResult]:
    """Run ``scenario`` once per seed: stepped together when it is :func:`batchable`, else one by one.

    Either way every result is the one :meth:`Simulation.run <amronet.sim.Simulation.run>` gives for its seed.
    """
    if len(seeds) > 1 and batchable(scenario):
        return BatchSimulation(scenario, seeds).run()
    return [Simulation(scenario, int(seed)).run() for seed in seeds]


class BatchSimulation:
    """Runs of one scenario with different seeds, stepped together; :meth:`run` returns one result per seed.

    Args:
        scenario: The validated scenario (see :func:`batchable`).
        seeds: One seed per run.
        omap: Use this map instead of loading the scenario's.

    Raises:
        ScenarioError: If the scenario cannot be batched, or a seed is invalid.
    """

    def __init__(self, scenario: Scenario, seeds: list[int], omap: OccupancyMap | None = None) -> None:
        if not batchable(scenario):
            raise ScenarioError("algorithm.name", f"runs of {scenario.algorithm.name!r} with "
                                f"{scenario.agents.per_base} agents per base cannot be stepped in batches; "
                                "run them one by one (amronet.sim.Simulation)")
        if not seeds:
            raise ScenarioError("seeds", "a batch needs at least one seed")
        self.scenario = scenario
        self.runs = [Simulation(scenario, int(seed), omap) for seed in seeds]
        sizes = [len(r.swarm) for r in self.runs]
        self.starts = np.concatenate([[0], np.cumsum(sizes)]).astype(np.int64)
        self.blocks = [slice(int(a), int(b)) for a, b in zip(self.starts[:-1], self.starts[1:], strict=True)]
        self.groups = np.repeat(np.arange(len(self.runs), dtype=np.int64), sizes)
        self.swarm = Swarm.concat([r.swarm for r in self.runs])
        for run, block in zip(self.runs, self.blocks, strict=True):
            run.swarm = self.swarm.rows(block)  # the run's metrics read its block of the shared arrays
        first = self.runs[0]
        self.world, self.medium, self.dt = first.world, first.medium, first.dt
        self.controller = ALGORITHMS[scenario.algorithm.name](
            scenario.algorithm_params(), self.swarm, self.world.omap, scenario.radio.r_c, self.dt,
            RunStreams([r.rng for r in self.runs], self.starts), scenario=scenario)
        self.table = self.medium.update(self.swarm.xy, self.groups)
        self.steps = 0

    @property
    def t(self) -> float:
        """Simulated time in seconds."""
        return self.steps * self.dt

    def step(self) -> None:
        """Advance every run by one step (sense → decide → move → radio), as :meth:`Simulation.step` does."""
        sw = self.swarm
        readings = sense(self.controller, sw, self.world.omap, self.table)
        command = self.controller.decide(StepInput(self.steps, self.t, self.dt, self.table, readings))
        move(self.controller, command, sw, self.world.omap, self.table, self.dt,
             self.scenario.sim.robot_collisions)
        self.table = self.medium.update(sw.xy, self.groups)
        self.steps += 1

    def _settled(self) -> np.ndarray:
        """Per run: no robot of it will move again."""
        moving = self.groups[self.controller.unsettled()]
        return np.bincount(moving, minlength=len(self.runs)) == 0

    def _record(self, g: int) -> bool:
        """Record run ``g``'s metrics now, as :meth:`Simulation.run` does; whether it reached its target."""
        run = self.runs[g]
        run.steps = self.steps
        run.table = self.table.block(self.blocks[g])
        return run._reached(run._record())

    def run(self) -> list[RunResult]:
        """Run every run until its stop condition holds; results in the order of the seeds.

        A run's ``wall_time_s`` is its share of the batch: the batch's wall time until the run stopped, divided
        by the number of runs in the batch.
        """
        sim = self.scenario.sim
        start = time.perf_counter()
        n = len(self.runs)
        results: list[RunResult | None] = [None] * n
        max_steps = round(sim.time_limit / self.dt)
        settled_at = np.where(self._settled(), 0.0, np.nan)
        active = []
        for g in range(n):
            if self._record(g):
                results[g] = self._finish(g, "coverage_target", settled_at[g], start)
            else:
                active.append(g)
        while active:
            self.step()
            now_settled = self._settled()
            settled_at[~now_settled] = np.nan
            settled_at[now_settled & np.isnan(settled_at)] = self.t
            at_limit = self.steps >= max_steps
            on_record = self.steps % sim.record_every == 0 or at_limit
            still = []
            for g in active:
                settled = sim.stop_when_settled and bool(now_settled[g])
                reached = (on_record or settled) and self._record(g)
                reason = ("coverage_target" if reached else "settled" if settled else "time_limit" if at_limit
                          else None)
                if reason is None:
                    still.append(g)
                else:
                    results[g] = self._finish(g, reason, settled_at[g], start)
            active = still
        return [r for r in results if r is not None]

    def _finish(self, g: int, reason: str, settled_at: float, start: float) -> RunResult:
        """Take run ``g`` out of the batch: its own copy of its robots, its final metrics and its result."""
        run = self.runs[g]
        run.steps = self.steps
        run.stop_reason = reason
        run.settled_at = None if np.isnan(settled_at) else float(settled_at)
        run.swarm = run.swarm.copy()
        run.table = self.table.block(self.blocks[g])
        final = run.metrics(method=self.scenario.sim.coverage_method)
        result = RunResult.from_simulation(run, final, wall_time_s=(time.perf_counter() - start) / len(self.runs))
        result.summary.update(self.controller.report_run(self.blocks[g]))
        return result
