"""One seeded run of a scenario: the loop of one run, stepped by ``step()`` or run to its end by ``run()``."""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING

import numpy as np

from amronet.engine.robots import Role
from amronet.scenario import Scenario
from amronet.sim.loop import Loop, StepKind
from amronet.sim.results import RunResult
from amronet.sim.run import Metrics
from amronet.world.occupancy import OccupancyMap

if TYPE_CHECKING:
    from amronet.outputs.recording import Recorder

__all__ = ["Simulation"]


class Simulation(Loop):
    """One seeded run of a scenario, stepped by :meth:`step` or run to its end by :meth:`run`: the loop of one run.

    Args:
        scenario: The validated scenario.
        seed: Seed of the run's random generator.
        omap: Use this map instead of loading the scenario's (for generated or scaled maps).
        force: Run even what the resource guard calls absurdly long (see :class:`Loop`).
        step: ``compiled`` or ``reference`` (see :class:`Loop`).
    """

    def __init__(self, scenario: Scenario, seed: int, omap: OccupancyMap | None = None, *,
                 force: bool = False, step: StepKind = "compiled") -> None:
        super().__init__(scenario, [seed], omap, force=force, step=step)
        self.books = self.runs[0]
        """The run's books (:class:`~amronet.sim.run.Run`): rows, stop reason, agents' connection."""
        self.seed = self.books.seed
        self.rng = self.books.rng
        self.bases = self.books.bases
        self.agents = self.books.agents
        self.coverage_target = self.books.coverage_target

    def run(self, progress: Callable[[float, float], None] | None = None, recorder: Recorder | None = None
            ) -> RunResult:
        """Run until a stop condition holds and return its result (see :meth:`Loop.execute`)."""
        return self.execute(progress, [recorder])[0]

    def metrics(self, method: str | None = None) -> Metrics:
        """Network metrics now (:meth:`amronet.sim.run.Run.metrics`)."""
        return self.books.metrics(method)

    @property
    def stop_reason(self) -> str | None:
        """Why the run ended (``None`` while it runs)."""
        return self.books.stop_reason

    @property
    def terminated(self) -> bool:
        """``True`` when the run ended because the task ended (settled or target reached), not by time."""
        return self.books.terminated

    @property
    def settled_at(self) -> float | None:
        """Start of the final stretch of time in which no router moved (``None`` while one still moves)."""
        return self.books.settled_at

    @property
    def agents_connected_fraction(self) -> float | None:
        """Mean over all steps of the fraction of agents connected to a base station (``None`` without agents)."""
        return self.books.agents_connected_fraction

    @property
    def agents_connected_min(self) -> float:
        """The lowest fraction of agents connected at any step."""
        return self.books.agents_connected_min

    def state_counts(self) -> dict[str, int]:
        """How many robots are in each state."""
        return self.books.state_counts()

    @property
    def rows(self) -> list[tuple]:
        """The recorded rows of the time series so far."""
        return self.books.rows

    def __repr__(self) -> str:
        n = {name: int(np.count_nonzero(self.swarm.role == code)) for name, code in
             (("bases", Role.BASE), ("routers", Role.ROUTER), ("agents", Role.AGENT))}
        return f"Simulation({self.scenario.name!r}, seed={self.seed}, t={self.t:g} s, {n})"
