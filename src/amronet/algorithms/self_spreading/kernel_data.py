"""What self-spreading's kernels (:mod:`amronet.algorithms.self_spreading.kernels`) read and keep, by name.

The controller's reference tracking (:class:`Tracking`), what the tracking lists (:class:`Tracked`), the random walk
(:class:`Walk`, :class:`Draws`), the moves' scratch (:class:`Moves`) and the walkers' generators (:class:`Streams`)
are ``NamedTuple`` s, as are the map's :class:`~amronet.engine.kernel_data.Grid`, the robots'
:class:`~amronet.algorithms.common.swarm_data.Robots`, the triangle routers'
:class:`~amronet.algorithms.common.goto.Steering` and the sensor ring, :class:`~amronet.engine.sensing.QuietRing`.

:class:`SpreadingData` holds them all for a loop: the fast step builds it once and hands it to every kernel call. It
is a numba *structref*, not a ``NamedTuple``: numba types a ``NamedTuple`` argument from Python field by field, names
included, at every call (numba 0.68: :func:`~amronet.algorithms.self_spreading.kernels.sense_steer_drive`'s 36 values
as six named tuples took 5.5 µs a call, as 36 loose arguments 1.4 µs); a structref is typed in one look-up (about
0.45 µs), whatever it holds. Its arrays are the controller's and the swarm's own, changed in place. What changes every
step (the neighbour lists, the movers' count, the draws) comes as plain arguments, for the same reason: a
:class:`~amronet.engine.kernel_data.Csr` costs about 0.6 µs to type and 0.25 µs to build, three of them a step more
than the nine arrays they hold.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numba import njit, types
from numba.experimental import structref

from amronet.algorithms.common.goto import Steering
from amronet.algorithms.common.swarm_data import KernelData, Robots, unliteral_fields
from amronet.algorithms.self_spreading.cells import Roomy
from amronet.algorithms.self_spreading.walks import WALKS, Walker
from amronet.engine.kernel_data import Csr, Grid
from amronet.engine.sensing import QuietRing

__all__ = ["Draws", "Moves", "SpreadingData", "Streams", "Tracked", "Tracking", "Walk", "walk_of"]


class Tracking(NamedTuple):
    """The exploring routers' reference tracking (:func:`~amronet.algorithms.common.references.track_row`)."""

    current: np.ndarray
    """``int64 (N,)``: each router's reference (-1: none), the controller's."""
    deployed: np.ndarray
    """``bool (n_states,)``: which states are deployed (:func:`~amronet.engine.robots.state_lookup`)."""
    is_ref: np.ndarray
    """``bool (N,)``: scratch, which robots are deployed now."""
    want_other: bool
    """Whether a reference of another status is looked for (several statuses, triangular deployments on)."""
    r_eff: float
    """A router stops where its nearest reference is this far; also the triangle routers' anchor reach."""
    r_c: float
    """The communication radius."""
    local: bool
    """The local triangular rule: two disabled references make no triangle."""
    disabled: np.ndarray
    """``bool (N,)``: the controller's disabled nodes (the local rule)."""
    by_signal: bool
    """The ``link-quality`` stop rule: the rows' distances are negated link margins, the stop is the smoothed
    margin's (:class:`~amronet.algorithms.common.link_quality.MarginSmoother`)."""
    smoothed: np.ndarray
    """``(N,)``: ``link-quality``: the smoother's values, the controller's (a dummy otherwise)."""
    alpha: float
    """``link-quality``: the smoother's weight of a new sample."""
    stop_margin_db: float
    """``link-quality``: stop where the smoothed best margin is below this."""
    loss_margin_db: float
    """``link-quality``: stop at once where the raw best margin is below this."""
    starts: bool
    """Whether a stretch starts the triangular deployments itself
    (:func:`~amronet.algorithms.self_spreading.triangle_kernels.settle_with_triangles`: the ``none`` and ``local``
    rules, where the controller needs no link test), instead of ending before a step in which one may start."""


class Tracked(NamedTuple):
    """What :func:`~amronet.algorithms.self_spreading.kernels.track_explorers` lists (scratch, ``(N,)`` each)."""

    explorers: np.ndarray
    """The exploring routers."""
    new_current: np.ndarray
    """Their references after tracking."""
    nearest: np.ndarray
    """Their nearest references' distances."""
    other: np.ndarray
    """The references of another status they heard (-1: none)."""
    movers: np.ndarray
    """The routers that move this step."""
    walkers: np.ndarray
    """The walkers among them."""
    started: np.ndarray
    """``int64 (N + 1,)``: how many routers a stretch sent to a triangle goal (entry 0), then their ids."""


class Walk(NamedTuple):
    """The exploring routers' walk (:mod:`~amronet.algorithms.self_spreading.walk_kernels`), flat for ``prange``.

    The arrays are the controller's :class:`~amronet.algorithms.self_spreading.walks.Walker`'s, and scratch.
    """

    refused: np.ndarray
    """``bool (N,)``: whose last move was refused, the controller's."""
    turn_sigma: float
    """The heading noise per step, radians."""
    rule: int
    """The walk rule's code (:data:`~amronet.algorithms.self_spreading.walk_kernels.RANDOM` and the others)."""
    r_c: float
    """The communication radius (``growth``'s push outward)."""
    follow: np.ndarray
    """``int64 (N,)``: steps left following an obstacle's edge."""
    side: np.ndarray
    """``int64 (N,)``: the side each router keeps the obstacle it follows on."""
    follow_steps: int
    """At most this many steps following an obstacle's edge."""
    growth_s: float
    """How long a deployed node counts as new, seconds."""
    deployed_at: np.ndarray
    """``(N,)``: when each node was first seen deployed."""
    field: np.ndarray
    """``(N,)``: scratch, the step's growth field."""
    deployed: np.ndarray
    """``bool (N,)``: scratch, which nodes are deployed."""
    queue: np.ndarray
    """``int64 (N,)``: scratch, the field's search queue."""
    hops: np.ndarray
    """``int64 (N,)``: scratch, the field's hop counts."""


def walk_of(walker: Walker, refused: np.ndarray) -> Walk:
    """The kernels' :class:`Walk` of the controller's ``walker`` and its ``refused`` flags (their arrays, in place)."""
    n = len(refused)
    return Walk(refused, float(walker.turn_sigma), WALKS.index(walker.rule), float(walker.r_c), walker.follow,
                walker.side, int(walker.follow_steps), float(walker.growth_s), walker.deployed_at, np.full(n, np.inf),
                np.zeros(n, dtype=np.bool_), np.zeros(n, dtype=np.int64), np.zeros(n, dtype=np.int64))


class Draws(NamedTuple):
    """The walkers' draws of a step, walker by walker (:func:`~amronet.engine.streams.normal_then_uniform`)."""

    normal: np.ndarray
    """Standard normals."""
    uniform: np.ndarray
    """Uniforms in ``[0, 1)``."""


class Moves(NamedTuple):
    """The movers' scratch, mover by mover (``(N, ...)`` each)."""

    scans: np.ndarray
    """``(N, n_beams)``: the rings."""
    length: np.ndarray
    """The step lengths."""
    slot: np.ndarray
    """The threaded step's: each mover's rank among the walkers."""
    free: np.ndarray
    """The threaded step's: whether the path is clear of obstacles."""
    planned: np.ndarray
    """``(N, 2)``, the threaded step's: where the move would end."""
    roomy: Roomy
    """The step and body for which the map's cells (the ring's ``quiet``) say whether a move has room
    (:func:`~amronet.algorithms.self_spreading.cells.drive_rooms`)."""


class Streams(NamedTuple):
    """The walkers' generators (:func:`~amronet.engine.streams.compiled_streams`)."""

    bitgens: np.ndarray
    """Each run's bit generator's address."""
    starts: np.ndarray
    """Run ``g`` owns robots ``starts[g]`` to ``starts[g + 1] - 1``."""


@structref.register
class SpreadingDataType(types.StructRef):
    """numba's type of :class:`SpreadingData`."""

    def preprocess_fields(self, fields: tuple) -> tuple:
        """Its fields' types, literals widened."""
        return unliteral_fields(fields)


class SpreadingData(KernelData):
    """Everything self-spreading's kernels read and keep for a loop, by name (see the module docstring).

    Args:
        grid: The map's grid.
        robots: The robots' arrays.
        tracking: The reference tracking.
        tracked: What the tracking lists.
        walk: The random walk.
        draws: The walkers' draws' buffers (``(N,)`` each).
        steering: The triangle routers' go-to-goal.
        ring: The movers' sensor ring, with the cells where it cannot meet the grid
            (:class:`~amronet.engine.sensing.QuietRing`; its ``quiet`` are the map's
            :func:`~amronet.algorithms.self_spreading.cells.cell_flags`).
        moves: The movers' scratch.
        no_bodies: An empty neighbour list (moves without collisions).
        collisions: Whether bodies collide.
        dt: The step, seconds.
    """

    def __new__(cls, grid: Grid, robots: Robots, tracking: Tracking, tracked: Tracked, walk: Walk, draws: Draws,
                steering: Steering, ring: QuietRing, moves: Moves, no_bodies: Csr, collisions: bool,
                dt: float) -> SpreadingData:
        """Build it through a cached kernel (numba's own constructor compiles anew in every process)."""
        parts = (grid, robots, tracking, tracked, walk, draws, steering, ring, moves, no_bodies, collisions, dt)
        return _new(*parts)._keep(*parts)


structref.define_constructor(SpreadingData, SpreadingDataType, [
    "grid", "robots", "tracking", "tracked", "walk", "draws", "steering", "ring", "moves", "no_bodies", "collisions",
    "dt"])
structref.define_boxing(SpreadingDataType, SpreadingData)


@njit(cache=True)
def _new(grid, robots, tracking, tracked, walk, draws, steering, ring, moves, no_bodies, collisions,
         dt):  # pragma: no cover - numba
    """A :class:`SpreadingData` built by a cached kernel (numba's own constructor compiles anew in every process)."""
    return SpreadingData(grid, robots, tracking, tracked, walk, draws, steering, ring, moves, no_bodies, collisions, dt)
