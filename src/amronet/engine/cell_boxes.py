"""The boxes of cells the coverage and signal kernels (:mod:`amronet.engine.hearing`) look at around a node.

The kernels walk a grid's cells in blocks of :data:`BLOCK` cells a side, and skip a block whose nearest cell centre
is too far for a link to be heard (:func:`block_gap`); :func:`node_box` gives the cells within a node's reach.
``cells`` is a grid's :class:`~amronet.engine.hearing.Cells`.
"""

from __future__ import annotations

import math

from numba import njit

__all__ = ["BLOCK", "block_gap", "node_box"]

BLOCK = 8
"""Cells per side of the blocks that the coverage and signal kernels cull as a whole (see
:func:`~amronet.engine.hearing.cells_of`)."""


@njit(cache=True, inline="always")
def block_gap(x, y, cells, bi, bj, rows, cols):  # pragma: no cover - numba
    """Distance from ``(x, y)`` to the nearest cell centre of block ``(bi, bj)`` (a lower bound)."""
    i0 = bi * BLOCK
    j0 = bj * BLOCK
    i1 = min(i0 + BLOCK - 1, rows - 1)
    j1 = min(j0 + BLOCK - 1, cols - 1)
    ylo = cells.oy + (i0 + 0.5) * cells.res
    yhi = cells.oy + (i1 + 0.5) * cells.res
    xlo = cells.ox + (j0 + 0.5) * cells.res
    xhi = cells.ox + (j1 + 0.5) * cells.res
    dx = xlo - x if x < xlo else (x - xhi if x > xhi else 0.0)
    dy = ylo - y if y < ylo else (y - yhi if y > yhi else 0.0)
    return math.sqrt(dx * dx + dy * dy)


@njit(cache=True, inline="always")
def node_box(x, y, reach, cells, rows, cols):  # pragma: no cover - numba
    """The cells ``i0..i1, j0..j1`` within ``reach`` of ``(x, y)`` on the grid (empty when ``i0 > i1``).

    ``reach`` may be infinite (the whole grid).
    """
    i0 = max(int(math.floor(max((y - reach - cells.oy) / cells.res, -1.0))), 0)
    i1 = min(int(math.floor(min((y + reach - cells.oy) / cells.res, float(rows)))), rows - 1)
    j0 = max(int(math.floor(max((x - reach - cells.ox) / cells.res, -1.0))), 0)
    j1 = min(int(math.floor(min((x + reach - cells.ox) / cells.res, float(cols)))), cols - 1)
    return i0, i1, j0, j1
