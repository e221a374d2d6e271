"""Many seeded runs of one scenario stepped together in one set of arrays: the loop with more runs.

A 30-robot step costs about 100 us, nearly all of it the fixed cost of Python and NumPy calls, not the work on
30 robots. :class:`BatchSimulation` is the :class:`~amronet.sim.loop.Loop` holding ``G`` runs of the same scenario:
their robots are concatenated block by block, the radio medium builds one neighbour table that never links
robots of different runs (:func:`~amronet.engine.neighbours.neighbour_csr` with groups), one controller decides
for all of them, and every random draw is split by run (:class:`~amronet.engine.streams.RunStreams`). The step
order, the metrics and the stop rules are the loop's, the same code as for one run.

Every run gives the same result bit for bit as :meth:`Simulation.run <amronet.sim.loop.Simulation.run>` with its
seed: it starts from the same positions (drawn from its own generator), no robot of another run is ever in its
neighbour table, its random numbers come from its own generator in its own order, and its metrics and stop rules
are evaluated on its own block.

Only controllers that declare :attr:`~amronet.algorithms.base.Controller.batchable` (self-spreading, DSSA and
the potential field) are batched, and only scenarios without agents; :func:`batchable` says which.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import TYPE_CHECKING

from amronet.algorithms import ALGORITHMS
from amronet.errors import ScenarioError
from amronet.scenario import Scenario
from amronet.sim.assemble import medium_needs_rng
from amronet.sim.loop import Loop, StepKind
from amronet.sim.simulation import Simulation
from amronet.world.occupancy import OccupancyMap

if TYPE_CHECKING:
    from amronet.sim.results import RunResult

__all__ = ["BatchSimulation", "batchable", "run_seeds"]


def batchable(scenario: Scenario) -> bool:
    """Whether runs of ``scenario`` can be stepped together by :class:`BatchSimulation`."""
    return (ALGORITHMS.lookup(scenario.algorithm.name, "algorithm.name").batchable and scenario.agents.per_base == 0
            and not medium_needs_rng(scenario) and not scenario.faults)


def run_seeds(scenario: Scenario, seeds: Sequence[int],
              on_result: Callable[[int, RunResult], None] | None = None) -> list[RunResult]:
    """Run ``scenario`` once per seed: stepped together when it is :func:`batchable`, else one by one.

    Either way every result is the one :meth:`Simulation.run <amronet.sim.loop.Simulation.run>` gives for its seed.
    ``on_result(k, result)`` is called as the run of ``seeds[k]`` finishes (in a batch, while the others go on).
    """
    if len(seeds) > 1 and batchable(scenario):
        return BatchSimulation(scenario, seeds).run(on_result)
    results = []
    for k, seed in enumerate(seeds):
        results.append(Simulation(scenario, int(seed)).run())
        if on_result is not None:
            on_result(k, results[-1])
    return results


class BatchSimulation(Loop):
    """Runs of one scenario with different seeds, stepped together; :meth:`run` returns one result per seed.

    Args:
        scenario: The validated scenario (see :func:`batchable`).
        seeds: One seed per run.
        omap: Use this map instead of loading the scenario's.
        step: ``compiled`` or ``reference`` (see :class:`~amronet.sim.loop.Loop`).

    Raises:
        ScenarioError: If the scenario cannot be batched, or a seed is invalid.
    """

    def __init__(self, scenario: Scenario, seeds: Sequence[int], omap: OccupancyMap | None = None, *,
                 step: StepKind = "compiled") -> None:
        if not batchable(scenario):
            raise ScenarioError("algorithm.name", f"runs of {scenario.algorithm.name!r} with "
                                f"{scenario.agents.per_base} agents per base cannot be stepped in batches; "
                                "run them one by one (amronet.sim.Simulation)")
        super().__init__(scenario, seeds, omap, step=step)

    def run(self, on_result: Callable[[int, RunResult], None] | None = None) -> list[RunResult]:
        """Run every run until its stop condition holds; results in the order of the seeds (see ``Loop.execute``).

        ``on_result(k, result)`` is called as the run of the ``k``-th seed stops, while the others go on.
        """
        return self.execute(on_result=on_result)
