"""Named structures that kernels take instead of long lists of loose arrays.

A kernel that reads the map's grid takes one :class:`Grid`; one that reads a neighbour list takes one :class:`Csr`.
Both are ``NamedTuple`` s, which numba compiles as tuples with named fields (``grid.res``, ``csr.indptr``): no
cost in the compiled code, one argument instead of three or five at the call. Algorithm packages define their own
named structures for their robots' arrays and their state beside their kernels.
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
