"""The stepping protocol: how the loop hands a step, or a stretch of steps, to an algorithm's fast step.

The loop (:mod:`amronet.sim.loop`) runs every step in one order -- faults, sense, decide, move, radio, metrics -- and
is the only one that advances the clock, the radio's neighbour table and the runs' books. An algorithm may offer a
*fast step* (:meth:`~amronet.algorithms.base.Controller.fast_step`): the sense, decide and move phases of its
controller done in compiled passes, bit for bit what the phases one by one do. The loop describes itself to the
algorithm once, in a :class:`StepContext` (the map, the robots' arrays, the radio's reach, whether runs are batched
or have faults or agents); a fast step keeps what it needs of it (:class:`Surroundings`: the map's grid, the rings,
the bodies near each robot) and never sees the loop.

Each step the loop calls :meth:`FastStep.step` with the step's :class:`~amronet.algorithms.base.StepInput` (step
index, time, the table). Between two recorded steps it may offer a stretch (:meth:`FastStep.stretch`): the fast
step takes up to ``limit`` steps in one compiled call, radio search included, and returns what happened
(:class:`Stretched`: steps taken, the table's new rows, the rest of a step it stopped in); the loop then advances the
clock and the table, closes the books it handed in (:class:`Watch`) and finishes that step.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING, NamedTuple

import numpy as np

from amronet.engine.kernel_data import grid_of
from amronet.engine.robots import RobotModel, Swarm
from amronet.engine.sensing import beam_angles, body_table
from amronet.engine.table import NeighbourTable

if TYPE_CHECKING:
    from amronet.world.occupancy import OccupancyMap

__all__ = [
    "CSR",
    "RESTORING_AGENTS",
    "RESTORING_ROUTERS",
    "AgentBooks",
    "Command",
    "FastStep",
    "Readings",
    "StepContext",
    "StepInput",
    "Stretched",
    "Surroundings",
    "Watch",
]

CSR = tuple[np.ndarray, np.ndarray, np.ndarray]
"""A neighbour list as ``(indptr, indices, dist)``."""


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



@dataclass(frozen=True)
class StepContext:
    """What the loop tells an algorithm's fast step about itself, once, when the loop starts.

    Attributes:
        omap: The map (its grid for the rings and the moves).
        swarm: The robots' arrays (every run's, block by block).
        groups: Run index of every robot in a batch, ``None`` for a single run.
        dt: Step length, seconds.
        collisions: Whether robots' bodies collide (``sim.robot_collisions``).
        faults: Whether nodes may fail in the run (``faults``). The loop fails them before it calls
            :meth:`FastStep.step`, and offers a stretch only where no node fails within it, and once one has, only
            to a fast step that :attr:`~FastStep.silences` failed nodes, and while a fault's damage is not repaired
            only to one that :attr:`~FastStep.restores`; a fast step that takes such a run must never move a failed
            robot (the phases' move gives it speed 0).
        agents: Whether the run has agents (or agents releasing routers).
        radio_reach: The farthest the radio's table reaches, metres.
        keeps_every_pair: Whether the radio's table lists every pair within ``radio_reach`` (the unit disk): what a
            stretch that searches the neighbours itself needs.
        link_inputs: What a stretch that builds the radio's tables itself needs of it
            (:attr:`~amronet.engine.radio.RadioMedium.stretch_inputs`: the margin inputs of the built-in
            path-loss law, whose links are the pairs within ``radio_reach`` with a margin ``>= 0``; without walls
            and shadowing, every pair), or ``None``: the radio's own tables only.
    """

    omap: OccupancyMap
    swarm: Swarm
    groups: np.ndarray | None
    dt: float
    collisions: bool
    faults: bool
    agents: bool
    radio_reach: float
    keeps_every_pair: bool
    link_inputs: tuple | None = None


class AgentBooks(NamedTuple):
    """The agents' connection books of a run, as arrays a stretch keeps in place step by step.

    The loop opens them before a stretch and closes them after (:meth:`amronet.sim.run.Run.connection_books`).
    """

    bases: np.ndarray
    """The run's base nodes."""
    relay_mask: np.ndarray
    """The nodes that relay (:attr:`amronet.sim.run.Run.relay_mask`)."""
    arrays: tuple
    """``(scratch, connected_steps, outages, longest, current, counts, sums)``."""


class Watch(NamedTuple):
    """What the loop's books must see of a stretch: the runs running, their settled state, the agents' books."""

    active: np.ndarray
    """Indices of the runs still running."""
    settled: np.ndarray
    """Per run, whether it is settled now (the books after the last step)."""
    agents: AgentBooks | None
    """The single run's agents' connection books (``None``: a run without agents, or a batch)."""
    silent: np.ndarray | None = None
    """Nodes that send nothing (failed ones; ``None``: none has failed), offered only to a fast step that
    :attr:`~FastStep.silences` them."""
    restoring: int = 0
    """0, or a fault's damage is not repaired yet (offered only to a fast step that :attr:`~FastStep.restores`):
    :data:`RESTORING_AGENTS` or :data:`RESTORING_ROUTERS`."""


RESTORING_AGENTS = 1
"""Every deployed router has a path to a base station, an agent has none: move no relay (base nodes, routers), and
stop after the first step at whose end every agent has one (the faults' books look there)."""
RESTORING_ROUTERS = 2
"""A deployed router has no path to a base station: move no relay, so that none can get one back in the stretch."""


@dataclass
class Stretched:
    """What a stretch did, for the loop to advance the clock, the table and the books.

    Attributes:
        steps: Steps taken whole (radio search included).
        csr: The neighbour table's rows after them (``None`` when no step was taken whole).
        finish: The rest of a step the stretch stopped in (its first phases were done in the stretch): the loop calls
            it with that step's input once the clock and the table are advanced, then ends the step as after any
            fast step (radio, books). ``None``: the stretch stopped between steps.
        non_finite: A robot's position became non-finite in the last step taken (the loop raises, as the table
            would).
        margin: With ``csr``, the margins of its pairs under the radio's path-loss law (``csr`` is then every pair
            within reach, the links those with a margin ``>= 0``; ``None``: every pair is a link).
    """

    steps: int
    csr: CSR | None = None
    finish: Callable[[StepInput], None] | None = None
    non_finite: bool = False
    margin: np.ndarray | None = None


class FastStep:
    """An algorithm's compiled sense-decide-move (the base of every fast step; see the module docstring)."""

    stretches: bool = False
    """Whether :meth:`stretch` may take steps in this loop at all (the loop then offers one before each step)."""
    restores: bool = False
    """Whether :meth:`stretch` may take steps while a fault's damage is not repaired (:attr:`Watch.restoring`)."""
    silences: bool = False
    """Whether :meth:`stretch` may take steps once nodes have failed (:attr:`Watch.silent`): its kernels then let no
    link of a failed node count (none is read, or all are dropped as the radio drops them), and the loop silences
    them in the table it makes of the stretch's pairs."""

    def step(self, now: StepInput) -> None:
        """Sense, decide and move once: what the loop's three phases and the controller do, bit for bit."""
        raise NotImplementedError

    def stretch(self, limit: int, now: StepInput, watch: Watch) -> Stretched | None:
        """Take up to ``limit`` unrecorded steps in one call, or ``None`` where none can be taken now (default)."""
        return None




class Surroundings:
    """The map's grid for the rings and the moves, the movers' sensor ring, and the bodies near each robot.

    Args:
        context: The loop's step context.
        model: The movers' robot model (one for all of them).
        movers: Mask or indices of the robots that may move when no robot is ever added or changed (self-spreading,
            the potential field): the reach within which two bodies may touch after a step is then fixed
            (:meth:`bodies`). ``None``: robots come and go (agent-assisted runs), reaches are given per step
            (:meth:`near`).
    """

    def __init__(self, context: StepContext, model: RobotModel, movers: np.ndarray | None = None) -> None:
        omap, swarm = context.omap, context.swarm
        self.swarm = swarm if movers is None else None
        """The robots whose largest body :meth:`largest_radius` follows (``None``: fixed reaches, it never changes)."""
        self.grid = grid_of(omap)
        """The map's grid as the kernels read it."""
        self.angles = beam_angles(model.sensor_beams)
        self.sensor_range = float(model.sensor_range)
        self.collisions = context.collisions
        self._biggest = (swarm.radius, float(swarm.radius.max()))
        self._empty: dict[int, CSR] = {}
        self.sense_reach = float(self.sensor_range + self._biggest[1])
        self.drive_reach = 0.0
        """Fixed reaches only: every pair that could touch after this step's longest move is this close (with room
        for rounding: the kernels' exact reach, from lengths rounded through speeds, is at most this)."""
        if movers is not None:
            fastest = float(swarm.max_speed[movers].max(initial=0.0))
            self.drive_reach = (2.0 * self._biggest[1] + 2.0 * fastest * context.dt) * (1.0 + 1e-9) + 1e-12

    def largest_radius(self) -> float:
        """The largest body radius now (kept while the robots stay the same: robots are only ever added)."""
        radius = self._biggest[0] if self.swarm is None else self.swarm.radius
        if radius is not self._biggest[0]:
            self._biggest = (radius, float(radius.max()))
        return self._biggest[1]

    def no_bodies(self, n: int) -> CSR:
        """An empty neighbour list of ``n`` robots."""
        if n not in self._empty:
            self._empty[n] = (np.zeros(n + 1, dtype=np.int64), np.zeros(0, dtype=np.int32), np.zeros(0))
        return self._empty[n]

    def near(self, xy: np.ndarray, table: NeighbourTable, reach: float) -> CSR:
        """Every pair of robots within ``reach`` (:func:`body_table`); none for a single robot."""
        return body_table(xy, reach, table) if len(xy) > 1 else self.no_bodies(len(xy))

    def bodies(self, xy: np.ndarray, table: NeighbourTable, sense: bool = True) -> tuple:
        """``(several, sense CSR, drive with bodies, drive CSR)`` for this step, with the fixed reaches."""
        several = len(xy) > 1
        s_csr = self.near(xy, table, self.sense_reach) if sense else self.no_bodies(len(xy))
        drive_bodies = self.collisions and several
        d_csr = self.near(xy, table, self.drive_reach) if drive_bodies else self.no_bodies(len(xy))
        return several, s_csr, drive_bodies, d_csr
