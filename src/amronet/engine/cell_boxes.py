"""The boxes of cells the coverage and signal kernels (:mod:`amronet.engine.hearing`) look at around a node.

The kernels walk a grid's cells in blocks of :data:`BLOCK` cells a side, and skip a block whose nearest cell centre
is too far for a link to be heard (:func:`block_gap`); :func:`node_box` gives the cells within a node's reach.
``cells`` is a grid's :class:`Cells` (:func:`cells_of`).
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numba import njit

from amronet.engine.shadowing import FieldGrid, values_on_grid

__all__ = ["BLOCK", "Cells", "block_gap", "cells_of", "named_cells", "node_box"]

BLOCK = 8
"""Cells per side of the blocks that the coverage and signal kernels cull as a whole (see
:func:`cells_of`)."""


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


class Cells(NamedTuple):
    """A grid whose cell centres the coverage and signal kernels decide, with the shadowing field there."""

    ox: float
    """x of the grid's lower-left corner, metres."""
    oy: float
    """y of the grid's lower-left corner, metres."""
    res: float
    """Cell size, metres."""
    field: np.ndarray
    """The shadowing field at every cell centre ``(rows, cols)`` (1x1 zeros without shadowing)."""
    block_field: np.ndarray
    """Its maximum over blocks of :data:`BLOCK` cells (1x1 zeros without shadowing)."""


def cells_of(shape: tuple[int, int], ox: float, oy: float, res: float, clip: float, field: FieldGrid) -> Cells:
    """The :class:`Cells` of a grid of ``shape`` cells of side ``res`` from ``(ox, oy)`` under a radio's shadowing.

    ``clip`` and ``field``: the radio's (:class:`~amronet.engine.hearing.HearingInputs`; ``clip`` 0: no shadowing).

    The kernels take it as a plain tuple in the fields' order (``tuple(cells)``, see :meth:`HearingInputs.plain`).

    The kernels bound a block's best margin by its nearest point and its largest field value, and skip the block
    when even that bound is below what they look for.
    """
    rows, cols = shape
    if clip == 0.0:
        return Cells(ox, oy, res, np.zeros((1, 1)), np.zeros((1, 1)))
    cy = oy + (np.arange(rows) + 0.5) * res
    cx = ox + (np.arange(cols) + 0.5) * res
    values = values_on_grid(field, cx, cy)
    nb_r, nb_c = -(-rows // BLOCK), -(-cols // BLOCK)
    padded = np.full((nb_r * BLOCK, nb_c * BLOCK), -np.inf)
    padded[:rows, :cols] = values
    return Cells(ox, oy, res, values, padded.reshape(nb_r, BLOCK, nb_c, BLOCK).max(axis=(1, 3)))


@njit(cache=True, inline="always")
def named_cells(t):  # pragma: no cover - numba
    """The :class:`Cells` of its plain tuple."""
    return Cells(t[0], t[1], t[2], t[3], t[4])
