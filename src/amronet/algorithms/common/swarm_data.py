"""Named structures the swarm algorithms' kernels share: the robots' arrays and the movers' sensor ring.

Like :class:`~amronet.engine.kernel_data.Grid` and :class:`~amronet.engine.kernel_data.Csr` they are ``NamedTuple``
s, which numba compiles as tuples with named fields: a kernel reads ``robots.xy`` and ``ring.angles``. Each algorithm
keeps its own state in named structures beside its kernels.

A fast step hands its kernels everything that stays the same for a loop in one *structref* built once (see
:mod:`amronet.algorithms.self_spreading.kernel_data`): numba types a ``NamedTuple`` argument field by field at every
call from Python (about 0.1 µs a field, 0.4 µs a tuple), a structref in one look-up, whatever it holds.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numba.core import types
from numba.experimental import structref

from amronet.engine.robots import Swarm

__all__ = ["KernelData", "Ring", "Robots", "robots_of", "unliteral_fields"]


class Robots(NamedTuple):
    """The robots' arrays the kernels read and move (the swarm's own arrays, changed in place)."""

    xy: np.ndarray
    """``(N, 2)``: positions, metres."""
    heading: np.ndarray
    """``(N,)``: headings, radians."""
    state: np.ndarray
    """``int8 (N,)``: each robot's :class:`~amronet.engine.robots.State`."""
    status: np.ndarray
    """``(N,)``: each router's status (the base station whose network it belongs to; -1: none)."""
    max_speed: np.ndarray
    """``(N,)``: top speeds, metres per second."""
    radius: np.ndarray
    """``(N,)``: body radii, metres."""
    distance: np.ndarray
    """``(N,)``: distance travelled, metres."""


def robots_of(swarm: Swarm) -> Robots:
    """The kernels' :class:`Robots` of ``swarm`` (its arrays, not copies: valid while no robot is added)."""
    return Robots(swarm.xy, swarm.heading, swarm.state, swarm.status, swarm.max_speed, swarm.radius, swarm.distance)


class Ring(NamedTuple):
    """The movers' range sensor ring."""

    angles: np.ndarray
    """``(n_beams,)``: the beams' angles from the heading (:func:`~amronet.engine.sensing.beam_angles`)."""
    sensor_range: float
    """A beam's reach, metres."""


def unliteral_fields(fields: tuple) -> tuple:
    """A structref's ``(name, type)`` fields with literal types widened (a constant gives no type of its own)."""
    return tuple((name, types.unliteral(t)) for name, t in fields)


class KernelData(structref.StructRefProxy):
    """The base of a fast step's structref: it keeps the values it was built from, and copies and pickles as them.

    A copy (``copy.deepcopy`` of a loop) is a new structref built from copies of those values, so that it holds the
    copied arrays, not the original ones.
    """

    _parts: tuple
    """The values it was built from, in its constructor's order."""

    def _keep(self, *parts: object) -> KernelData:
        self._parts = parts
        return self

    def __reduce__(self) -> tuple:
        return type(self), self._parts
