"""What a deployment algorithm is: a controller that turns one step's local information into motion.

Controllers see only what the robots can sense or hear: their own range readings and their own row of the
radio medium's neighbour table (who is within ``r_c``, how far, and what those neighbours announce: state and
status). Metrics and stop conditions live in :mod:`amronet.sim`, not here.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING, ClassVar

import numpy as np
from pydantic import BaseModel

from amronet.radio import NeighbourTable
from amronet.robots import Swarm
from amronet.world.occupancy import OccupancyMap

if TYPE_CHECKING:
    from amronet.scenario import Scenario
    from amronet.streams import RunStreams

__all__ = ["ALGORITHMS", "Command", "Controller", "Readings", "StepInput", "register_algorithm"]


@dataclass(frozen=True)
class Readings:
    """Range readings of the robots that were sensed this step, grouped by robot model.

    Attributes:
        groups: ``model index → (robot indices (M,), ranges (M, n_beams))``.
    """

    groups: dict[int, tuple[np.ndarray, np.ndarray]]

    def of(self, robots: np.ndarray, model: int) -> np.ndarray:
        """Readings of the given robots, all of robot model ``model`` and all sensed this step."""
        who, scans = self.groups[model]
        if len(who) == len(robots) and (who == robots).all():
            return scans
        slot = np.searchsorted(who, robots)
        return scans[slot]


@dataclass(frozen=True)
class StepInput:
    """Everything a controller may use in one step.

    Attributes:
        index: Step number, starting at 0.
        t: Simulated time at the start of the step, seconds.
        dt: Step length, seconds.
        table: The radio medium's neighbour table for the current positions.
        readings: This step's range readings of the mobile robots.
    """

    index: int
    t: float
    dt: float
    table: NeighbourTable
    readings: Readings


@dataclass(frozen=True)
class Command:
    """The motion a controller asks for: robots ``movers`` drive at ``speed`` along their (updated) headings."""

    movers: np.ndarray
    speed: np.ndarray


class Controller(ABC):
    """Base class of deployment algorithms.

    Args:
        params: Validated parameters (an instance of :attr:`Params`).
        swarm: The run's robots; the controller updates headings, states and statuses in place.
        omap: The map (for nothing but its geometry's sake; controllers do not read obstacles from it).
        r_c: Communication radius.
        dt: Step length.
        rng: The run's random generator; for a batch of runs, their :class:`~amronet.streams.RunStreams`.
        scenario: The whole scenario, for controllers that need more (e.g. the robot kind agents release).

    Batching (:mod:`amronet.batch`): a controller with :attr:`batchable` set can drive several runs at once, their
    robots concatenated into one swarm and one neighbour table that never links robots of different runs. It
    must then keep every run independent of the others: per-robot state only, no reductions over all robots that
    feed back into decisions, every random draw through :func:`~amronet.streams.draw_per_run`, and
    :meth:`unsettled` and :meth:`report_run` to answer per run.
    """

    name: ClassVar[str]
    Params: ClassVar[type[BaseModel]]
    batchable: ClassVar[bool] = False
    """Whether the controller can step several runs in one swarm (see the class docstring)."""

    def __init__(
        self,
        params: BaseModel,
        swarm: Swarm,
        omap: OccupancyMap,
        r_c: float,
        dt: float,
        rng: np.random.Generator | RunStreams,
        scenario: Scenario | None = None,
    ) -> None:
        self.scenario = scenario
        self.params = params
        self.swarm = swarm
        self.omap = omap
        self.r_c = r_c
        self.dt = dt
        self.rng = rng

    @abstractmethod
    def decide(self, step: StepInput) -> Command:
        """Update states and headings from local information and say who moves how fast."""

    @property
    def needs_range_readings(self) -> bool:
        """``False`` when :meth:`decide` never reads ``step.readings`` (the sense phase then skips ray casting).

        Sensing has no randomness, so skipping it changes nothing but the time a step takes.
        """
        return True

    def after_move(self, movers: np.ndarray, refused: np.ndarray) -> None:  # noqa: B027 - optional hook
        """Learn which of the requested moves the world refused (default: ignore)."""

    def report(self) -> dict[str, object]:
        """Algorithm-specific numbers for the run's summary (default: none)."""
        return {}

    def unsettled(self) -> np.ndarray:
        """Mask ``(N,)`` of the robots that may still move (batchable controllers; :attr:`settled` per run)."""
        raise NotImplementedError(f"{type(self).__name__} does not step runs in batches")

    def report_run(self, robots: slice) -> dict[str, object]:
        """:meth:`report` of the run whose robots are ``robots`` in a batch (default: :meth:`report`)."""
        return self.report()

    @property
    @abstractmethod
    def settled(self) -> bool:
        """``True`` when no robot of the algorithm will move again."""


ALGORITHMS: dict[str, type[Controller]] = {}


def register_algorithm(name: str) -> Callable[[type[Controller]], type[Controller]]:
    """Class decorator that registers a controller under ``name`` for scenarios and the CLI."""

    def deco(cls: type[Controller]) -> type[Controller]:
        cls.name = name
        ALGORITHMS[name] = cls
        return cls

    return deco
