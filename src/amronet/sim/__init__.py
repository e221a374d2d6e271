"""Running scenarios: assembling a run from a scenario, the one step loop, batches of runs, and their results.

:class:`Simulation` is one seeded run, stepped by ``step()`` or run to its end by ``run()``;
:class:`BatchSimulation` steps many runs of one scenario in one set of arrays; :func:`run` runs a scenario
and returns its :class:`RunResult`.
"""

from amronet.sim.api import run
from amronet.sim.batch import BatchSimulation, batchable, run_seeds
from amronet.sim.loop import Metrics, move, sense
from amronet.sim.results import RunResult
from amronet.sim.simulation import Simulation

__all__ = ["BatchSimulation", "Metrics", "RunResult", "Simulation", "batchable", "move", "run", "run_seeds", "sense"]
