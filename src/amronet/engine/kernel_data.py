"""Named structures that kernels take instead of long lists of loose arrays.

A kernel that reads the map's grid takes one :class:`Grid`; one that reads a neighbour list takes one :class:`Csr`.
Inside compiled code a ``NamedTuple`` costs nothing (``grid.res``, ``csr.indptr``). At a call *from Python* numba
types a NamedTuple by its class and field names, 1-2 us each (measured: a plain tuple 0.5 us, a named one 2.2 us),
so the per-step calls from Python pass plain tuples laid out as these classes (``tuple(grid)``, or the fields in
their order), and the kernels read them by position or rebuild the named structure inside; data that stays fixed
for a run may instead travel in one numba structref built once (self-spreading's and the potential field's
``kernel_data.py``: about 0.45 us a call whatever it holds). Algorithm packages define their own named structures
for their robots' arrays and their state beside their kernels.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from amronet.world.occupancy import OccupancyMap
from amronet.world.space import clearance

__all__ = ["Csr", "Grid", "grid_of"]


class Grid(NamedTuple):
    """The map as the kernels read it: which cells are blocked, how far each cell is from one, where and how fine."""

    blocked: np.ndarray
    """``uint8 (H, W)``: 1 where a cell is an obstacle (the occupancy map's ``blocked`` viewed as bytes)."""
    clear: np.ndarray
    """``(H, W)``: each cell's clearance, metres (:func:`amronet.world.space.clearance`)."""
    ox: float
    """x of the map's lower-left corner, metres."""
    oy: float
    """y of the map's lower-left corner, metres."""
    res: float
    """Cell size, metres."""


class Csr(NamedTuple):
    """A neighbour list in compressed sparse rows: row ``i``'s neighbours are ``indices[indptr[i]:indptr[i + 1]]``."""

    indptr: np.ndarray
    """``int64 (N + 1,)``: where each row starts."""
    indices: np.ndarray
    """``(nnz,)``: the neighbours, row after row."""
    dist: np.ndarray
    """``(nnz,)``: their distances, metres."""


def grid_of(omap: OccupancyMap) -> Grid:
    """The kernels' :class:`Grid` of ``omap`` (its clearance is computed once per map and cached)."""
    return Grid(omap.blocked.view(np.uint8), clearance(omap), float(omap.origin[0]), float(omap.origin[1]),
                float(omap.resolution))
