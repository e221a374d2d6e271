"""What the potential field's kernels (:mod:`amronet.algorithms.potential_field.kernels`) read and keep, by name.

The controller's force, velocity and rest state (:class:`FieldState`), its constants (:class:`FieldConstants`) and the
fast step's scratch (:class:`FieldScratch`) are ``NamedTuple`` s, as are the map's
:class:`~amronet.engine.kernel_data.Grid`, the robots' :class:`~amronet.algorithms.common.swarm_data.Robots` and the
:class:`~amronet.algorithms.common.swarm_data.Ring`. :class:`FieldData` holds them all for a loop, a numba structref
built once by the fast step, for the reason given in :mod:`amronet.algorithms.self_spreading.kernel_data`.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any, NamedTuple, Protocol

import numpy as np
from numba import njit, types
from numba.experimental import structref

from amronet.algorithms.common.swarm_data import KernelData, Ring, Robots, unliteral_fields
from amronet.engine.kernel_data import Csr, Grid

__all__ = ["FieldConstants", "FieldData", "FieldScratch", "FieldState", "field_constants_of", "field_state_of"]


class FieldControls(Protocol):
    """What the fast step reads and keeps of its controller: nothing else of it.

    The controller is :class:`~amronet.algorithms.potential_field.controller.PotentialField`: its names below are
    the declared interface between the two.
    """

    params: Any
    routers: np.ndarray
    needs_range_readings: bool
    k_obstacle: float
    force_cap: float
    k_cover: float
    k_degree: float
    q_rc: float
    obstacle_force: np.ndarray
    velocity: np.ndarray
    rest_count: np.ndarray
    window_start: np.ndarray
    force: np.ndarray
    held_force: np.ndarray
    wakeups: np.ndarray
    settling_rule: Callable[[], tuple[np.ndarray, np.ndarray]]


class FieldState(NamedTuple):
    """The controller's per-robot state (``(N, 2)`` or ``(N,)`` each), changed in place."""

    obstacle_force: np.ndarray
    """The obstacles' push, from each router's last ring."""
    velocity: np.ndarray
    """Velocities, metres per second."""
    rest_count: np.ndarray
    """``int64``: steps since the rest window started."""
    window_start: np.ndarray
    """Where the rest window started."""
    force: np.ndarray
    """The net force of the last step."""
    held_force: np.ndarray
    """The force a resting router rests under (it wakes when its force leaves it)."""
    wakeups: np.ndarray
    """``int64``: how often each router woke up."""


class FieldConstants(NamedTuple):
    """The field's constants (Poduri & Sukhatme's constrained coverage, the obstacles' push, the dynamics, the rest)."""

    k_obstacle: float
    """The obstacles' force constant."""
    cap: float
    """The largest force of one link or beam."""
    k_cover: float
    """The coverage (repulsion) constant."""
    k_degree: float
    """The degree (attraction) constant."""
    q_rc: float
    """Links shorter than this pull."""
    k_conn: int
    """The degree each router keeps (``K``)."""
    damping: float
    """Viscous friction."""
    mass: float
    """A router's mass."""
    dt: float
    """The step, seconds."""
    rest_fraction: float
    """A router at rest drifts less than this fraction of its top speed."""
    rest_steps: int
    """The rest window, steps."""


class FieldScratch(NamedTuple):
    """The fast step's scratch."""

    scan: np.ndarray
    """``(n_beams,)``: one router's ring."""
    movers: np.ndarray
    """``int64 (n_routers,)``: the routers that move."""
    speed: np.ndarray
    """``(n_routers,)``: their speeds."""
    refused: np.ndarray
    """``bool (n_routers,)``: whose move was refused."""


def field_state_of(controller: FieldControls) -> FieldState:
    """The kernels' :class:`FieldState` of the controller's arrays (not copies)."""
    c = controller
    return FieldState(c.obstacle_force, c.velocity, c.rest_count, c.window_start, c.force, c.held_force, c.wakeups)


def field_constants_of(controller: FieldControls, dt: float) -> FieldConstants:
    """The kernels' :class:`FieldConstants` of the controller, for steps of ``dt`` seconds."""
    c, p = controller, controller.params
    return FieldConstants(float(c.k_obstacle), float(c.force_cap), float(c.k_cover), float(c.k_degree), float(c.q_rc),
                          int(p.connectivity_k), float(p.damping), float(p.mass), float(dt), float(p.rest_fraction),
                          int(p.rest_steps))


@structref.register
class FieldDataType(types.StructRef):
    """numba's type of :class:`FieldData`."""

    def preprocess_fields(self, fields: tuple) -> tuple:
        """Its fields' types, literals widened."""
        return unliteral_fields(fields)


class FieldData(KernelData):
    """Everything the potential field's kernels read and keep for a loop, by name (see the module docstring).

    Args:
        grid: The map's grid.
        robots: The robots' arrays.
        routers: ``int64``: the routers.
        ring: The routers' sensor ring.
        field: The controller's state.
        constants: Its constants.
        scratch: The fast step's scratch.
        no_bodies: An empty neighbour list (rings or moves without bodies).
        collisions: Whether bodies collide.
        sense: Whether the routers read their rings (the obstacles' forces).
    """

    def __new__(cls, grid: Grid, robots: Robots, routers: np.ndarray, ring: Ring, field: FieldState,
                constants: FieldConstants, scratch: FieldScratch, no_bodies: Csr, collisions: bool,
                sense: bool) -> FieldData:
        """Build it through a cached kernel (numba's own constructor compiles anew in every process)."""
        parts = (grid, robots, routers, ring, field, constants, scratch, no_bodies, collisions, sense)
        return _new(*parts)._keep(*parts)


structref.define_constructor(FieldData, FieldDataType, [
    "grid", "robots", "routers", "ring", "field", "constants", "scratch", "no_bodies", "collisions", "sense"])
structref.define_boxing(FieldDataType, FieldData)


@njit(cache=True)
def _new(grid, robots, routers, ring, field, constants, scratch, no_bodies, collisions,
         sense):  # pragma: no cover - numba
    """A :class:`FieldData` built by a cached kernel."""
    return FieldData(grid, robots, routers, ring, field, constants, scratch, no_bodies, collisions, sense)
