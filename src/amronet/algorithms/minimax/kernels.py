"""Minimax's compiled geometry: the centre of the smallest circle enclosing each cell's vertices.

The incremental algorithm (Welzl's, iterative: a point outside the circle so far lies on the new circle's boundary,
with one or two points found before it), over each cell's vertices in their order: a cell has a few dozen vertices,
so the worst case, cubic in them, stays small; no random order is needed.
"""

from __future__ import annotations

import numba
import numpy as np

from amronet.algorithms.common.polygons import Polygons

__all__ = ["enclosing_centres"]

_SLACK = 1e-12
"""A vertex within this fraction of the radius outside the circle is in it (rounding; our choice)."""


@numba.njit(cache=True, inline="always")
def _outside(x, y, cx, cy, r2):  # pragma: no cover - numba
    dx, dy = x - cx, y - cy
    return dx * dx + dy * dy > r2 * (1.0 + _SLACK) ** 2


@numba.njit(cache=True, inline="always")
def _circumcentre(ax, ay, bx, by, cx, cy):  # pragma: no cover - numba
    """The centre of the circle through three points (of two of them, the farthest apart, when in one line)."""
    bx, by, cx, cy = bx - ax, by - ay, cx - ax, cy - ay
    d = 2.0 * (bx * cy - by * cx)
    b2, c2 = bx * bx + by * by, cx * cx + cy * cy
    if d == 0.0:
        dc = (bx - cx) ** 2 + (by - cy) ** 2
        if b2 >= c2 and b2 >= dc:
            return ax + 0.5 * bx, ay + 0.5 * by
        if c2 >= dc:
            return ax + 0.5 * cx, ay + 0.5 * cy
        return ax + 0.5 * (bx + cx), ay + 0.5 * (by + cy)
    return ax + (cy * b2 - by * c2) / d, ay + (bx * c2 - cx * b2) / d


@numba.njit(cache=True)
def _enclosing(xy, count, out):  # pragma: no cover - numba
    for m in range(xy.shape[0]):
        n = count[m]
        if n < 3:  # no cell (or a degenerate one): no move
            continue
        p = xy[m]
        cx, cy, r2 = p[0, 0], p[0, 1], 0.0
        for i in range(1, n):
            if not _outside(p[i, 0], p[i, 1], cx, cy, r2):
                continue
            cx, cy, r2 = p[i, 0], p[i, 1], 0.0
            for j in range(i):
                if not _outside(p[j, 0], p[j, 1], cx, cy, r2):
                    continue
                cx, cy = 0.5 * (p[i, 0] + p[j, 0]), 0.5 * (p[i, 1] + p[j, 1])
                r2 = (p[i, 0] - cx) ** 2 + (p[i, 1] - cy) ** 2
                for k in range(j):
                    if not _outside(p[k, 0], p[k, 1], cx, cy, r2):
                        continue
                    cx, cy = _circumcentre(p[i, 0], p[i, 1], p[j, 0], p[j, 1], p[k, 0], p[k, 1])
                    r2 = (p[i, 0] - cx) ** 2 + (p[i, 1] - cy) ** 2
        out[m, 0] = cx
        out[m, 1] = cy


def enclosing_centres(cells: Polygons) -> np.ndarray:
    """The centre ``(M, 2)`` of the smallest circle enclosing each cell's vertices (a cell of fewer than 3: 0)."""
    out = np.zeros((len(cells.count), 2))
    _enclosing(np.ascontiguousarray(cells.xy, dtype=np.float64), cells.count.astype(np.int64), out)
    return out
