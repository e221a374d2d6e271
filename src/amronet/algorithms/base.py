"""What a deployment algorithm is: a controller that turns one step's local information into motion.

A controller is given, once, a :class:`Setup`: the state arrays of the robots it drives (each robot's own position,
heading, state and status, and what it announces on the air), the radio range, the step length, the run's random
generator, what the algorithm may know of the area beforehand (:class:`AreaKnowledge`: its bounding box and free
floor area, never the map) and, for agents that carry routers, their :class:`RouterStock` and the paths the scenario
gives them, if any. Each step it is given a :class:`StepInput`: the range readings of its robots and the radio
medium's neighbour table (who hears whom, how far). A robot's decision reads its own rows and the rows of the nodes
it hears; nothing else of the world reaches a controller: not the map, not the scenario, not the loop. Metrics and
stop conditions live in :mod:`amronet.sim`, not here. What the loop needs to know of an algorithm it asks through
the declared interface below (:meth:`Controller.start_range`, :attr:`Controller.default_coverage_target`,
:meth:`Controller.unsettled`, :meth:`Controller.fast_step`); what the scenario needs to know (its parameters'
model, its scenario defaults, whether it follows given paths), through its declaration
(:mod:`amronet.algorithms.declaration`), which does not import the controller.
"""

from __future__ import annotations

import importlib
import importlib.util
from abc import ABC, abstractmethod
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, ClassVar, Literal

import numpy as np
from pydantic import BaseModel

from amronet.algorithms.declaration import ALGORITHMS
from amronet.algorithms.stepping import Command, Readings, StepInput
from amronet.engine.robots import RobotModel, Swarm

if TYPE_CHECKING:
    from amronet.algorithms.stepping import FastStep, StepContext
    from amronet.engine.streams import RunStreams
    from amronet.world.trajectories import AgentPaths

__all__ = [
    "ALGORITHMS",
    "AreaKnowledge",
    "Command",
    "Controller",
    "Readings",
    "RouterStock",
    "Setup",
    "StepInput",
    "WarmUp",
]


@dataclass(frozen=True)
class AreaKnowledge:
    """What an algorithm may know of the area before it starts: its size, never its obstacles.

    Attributes:
        extent: ``(xmin, xmax, ymin, ymax)`` of the area in metres (e.g. the size of the map agents build).
        free_area_m2: The free floor area, m² (e.g. DSSA's field area for its expected density).
    """

    extent: tuple[float, float, float, float]
    free_area_m2: float


@dataclass(frozen=True)
class RouterStock:
    """The routers that agents carry and release.

    Attributes:
        robot: The released routers' robot model.
        per_agent: Routers each agent carries (``None``: unlimited).
        path_clear: The agent's hand: ``path_clear(start (M, 2), end (M, 2), radius (M,))`` says which bodies of
            the given radii could be put down along those segments without touching an obstacle.
        when_empty: What an agent with no router left does: ``tether`` or ``continue`` (``agents.when_empty``).
        settle_s: Seconds before a router put down relays (``agents.drop_settle_s``).
        reverse_after_s: Seconds out of contact before an agent backs up to drop (``agents.reverse_drop``;
            ``None``: never).
    """

    robot: RobotModel
    per_agent: int | None
    path_clear: Callable[[np.ndarray, np.ndarray, np.ndarray], np.ndarray]
    when_empty: str = "tether"
    settle_s: float = 0.0
    reverse_after_s: float | None = None


@dataclass(frozen=True)
class Setup:
    """Everything a controller is given when its run starts.

    Attributes:
        robots: The state arrays of the robots (positions, headings, states, statuses; one row per node on the
            air). The controller updates headings, states and statuses of the robots it drives in place, and
            reads other nodes' rows only for the nodes its robots hear (the neighbour table's rows).
        r_c: Communication radius, metres.
        dt: Step length, seconds.
        rng: The run's random generator; for a batch of runs, their :class:`~amronet.engine.streams.RunStreams`.
        area: What the algorithm may know of the area beforehand.
        stock: The routers agents carry (``None`` without agents).
        paths: The agents' given paths (``agents.trajectories``; agent ``a`` is the ``a``-th agent of ``robots``),
            or ``None``: the agents explore. Only a controller declared ``follows_paths`` is given any
            (:class:`~amronet.algorithms.declaration.Declaration`).
        links_by_distance: Whether the radio links every pair within ``r_c`` and no other (the unit disk without
            packet loss): then a node within ``r_c`` is heard, and a rule that keeps a robot within ``r_c`` of a node
            keeps their link. Otherwise (walls, shadowing, packet loss) only the neighbour table says who hears whom.
            A robot would learn this from its own table row; it is told once so that the rules can skip link tests
            that cannot fail (and keep the paper's timing, bit for bit) where it holds.
    """

    robots: Swarm
    r_c: float
    dt: float
    rng: np.random.Generator | RunStreams
    area: AreaKnowledge
    stock: RouterStock | None = None
    paths: AgentPaths | None = None
    links_by_distance: bool = True


@dataclass(frozen=True)
class WarmUp:
    """A short run that compiles kernels this algorithm's runs use, ahead of a first run (:mod:`amronet.sim.warmup`).

    Attributes:
        label: What the run warms up, for the report (``algorithm NAME`` for the algorithm with its defaults).
        preset: The built-in scenario.
        overrides: Dotted-path fields to replace.
        seeds: One seed: a single run; several: one batch of them (the batched kernels).
        seconds: Simulated seconds.
        threaded: Run the kernels that large runs run on several threads (:mod:`amronet.threads`).
        step: The loop's step (``reference``: phase by phase, as the runs a fast step does not cover).
        first: One of the runs that compile the longest chains of kernels (tens of seconds): with several jobs they
            start first, so that the other jobs compile the rest meanwhile.
    """

    label: str
    preset: str
    overrides: dict[str, Any] = field(default_factory=dict)
    seeds: tuple[int, ...] = (1,)
    seconds: float = 3.0
    threaded: bool = False
    step: Literal["compiled", "reference"] = "compiled"
    first: bool = False


class Controller(ABC):
    """Base class of deployment algorithms.

    Args:
        params: Validated parameters (an instance of :attr:`Params`).
        setup: The robots and what the algorithm is given (:class:`Setup`).

    Batching (:mod:`amronet.sim.batch`): a controller with :attr:`batchable` set can drive several runs at once, their
    robots concatenated into one swarm and one neighbour table that never links robots of different runs. It
    must then keep every run independent of the others: per-robot state only, no reductions over all robots that
    feed back into decisions, every random draw through :func:`~amronet.engine.streams.draw_per_run`, and
    :meth:`report_run` to answer per run.
    """

    name: ClassVar[str]
    Params: ClassVar[type[BaseModel]]
    batchable: ClassVar[bool] = False
    """Whether the controller can step several runs in one swarm (see the class docstring)."""
    default_coverage_target: ClassVar[float | None] = None
    """The coverage at which a run of this algorithm ends when the scenario sets none (``None``: no target)."""

    def __init__(self, params: BaseModel, setup: Setup) -> None:
        self.params = params
        self.swarm = setup.robots
        self.r_c = setup.r_c
        self.dt = setup.dt
        self.rng = setup.rng
        self.area = setup.area
        self.links_by_distance = setup.links_by_distance

    @classmethod
    def start_range(cls, params: BaseModel, r_c: float) -> float:
        """How far from its base node a robot may start, so that it hears the base (default ``0.95 r_c``)."""
        return (1.0 - 0.05) * r_c

    @classmethod
    def warm_ups(cls) -> list[WarmUp]:
        """The short runs that compile this algorithm's kernels (its rules, its fast step), the defaults' run first.

        A test checks that every registered algorithm has them and that an algorithm with a fast step reaches it.
        By default: ``warm_ups()`` of the ``warmups`` module beside the controller's, none if there is no such module.
        """
        package = cls.__module__.rpartition(".")[0]
        if not package or importlib.util.find_spec(f"{package}.warmups") is None:
            return []
        return importlib.import_module(f"{package}.warmups").warm_ups()

    @abstractmethod
    def decide(self, step: StepInput) -> Command:
        """Update states and headings from local information and say who moves how fast."""

    @property
    def needs_range_readings(self) -> bool:
        """``False`` when :meth:`decide` never reads ``step.readings`` (the sense phase then skips ray casting).

        Sensing has no randomness, so skipping it changes nothing but the time a step takes.
        """
        return True

    def fast_step(self, context: StepContext) -> FastStep | None:
        """This controller's fast step in the loop ``context`` describes (:mod:`amronet.algorithms.stepping`).

        A fast step does the sense, decide and move phases of this controller in compiled passes, bit for bit what
        the phases one by one give. ``None`` (the default, and wherever the algorithm's fast step does not cover the
        loop's rules): the loop runs the phases one by one through :meth:`decide`.
        """
        return None

    def after_move(self, movers: np.ndarray, refused: np.ndarray) -> None:  # noqa: B027 - optional hook
        """Learn which of the requested moves the world refused (default: ignore)."""

    def report(self) -> dict[str, object]:
        """Algorithm-specific numbers for the run's summary (default: none)."""
        return {}

    def mission_report(self) -> dict[str, object]:
        """Numbers for the summary's ``mission`` section (default: none), e.g. ``relays_used``."""
        return {}

    def report_run(self, robots: slice) -> dict[str, object]:
        """:meth:`report` of the run whose robots are ``robots`` in a batch (default: :meth:`report`)."""
        return self.report()

    @abstractmethod
    def unsettled(self) -> np.ndarray:
        """Mask ``(N,)`` of the robots that may still move; a run whose robots are all settled has ended."""

    @property
    def settled(self) -> bool:
        """``True`` when no robot of the algorithm will move again."""
        return not self.unsettled().any()

