"""Cells certainly behind a wall as seen from a node: how coverage under walls skips most of its wall walks.

Where a link's budget allows no wall (its margin before walls is below one wall's loss), a cell is heard exactly
when the straight line from the node to the cell's centre meets no wall cell, which the wall walk
(:func:`~amronet.engine.wall_bits.count_walls_bits`) answers cell by cell; in a building most such cells lie behind
a wall. :func:`shade` draws, once per node, the shadows of the wall cells around it: per bin of directions (a
pseudo-angle, :func:`pseudo_angle`), the squared distance beyond which every line from the node in those
directions has passed through the inside of some wall cell. :func:`behind` then tells in a few operations whether a
point lies beyond that distance in its direction: the line to it crosses a wall cell, which the walk visits and
counts, so the count is at least one and the budget is not met. A point not found behind is walked as before.

Why it is exact: each wall cell is shrunk by :data:`SHRINK` of a cell on every side; a bin is shaded by a cell only
when the bin lies inside the cell's range of directions with :data:`EPS` to spare on both ends, and a point only
when its squared distance exceeds that of the cell's farthest corner by a relative 1e-9. A line whose direction lies
strictly inside the range of a convex square it does not start in passes through the square's inside, and leaves
it no farther than its farthest corner. The rounding of these few operations (of the order of 1e-15) is far below
the margins, and the walk itself visits every cell whose inside the segment crosses by a hundredth of a cell (its
leaps cross free cells only). Wall cells less than :data:`NEAR` cells from the node cast no shadow.

The same pass also draws where the node's lines are certainly **clear**: per bin, the squared distance to the nearest
wall cell, grown by :data:`SHRINK` of a cell on every side, whose directions reach into the bin (with :data:`EPS` to
spare). :func:`clear` tells whether a point is nearer than that (by a relative 1e-9): the segment to it then comes
no nearer than a hundredth of a cell to any wall cell, so the walk, which visits only cells the segment passes
through (rounding aside, of the order of 1e-12 of a cell), counts no wall. That answers the cells in sight of the
node without a walk or a box test. A node in a grown wall cell, or outside the map (a wall to the walk),
has no clear line.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit
from numba import uint64 as _u

__all__ = ["BINS", "behind", "clear", "dark", "look", "pseudo_angle", "shade"]

BINS = 4096
"""Bins of directions around a node (a quarter turn is :data:`BINS` / 4 of them)."""
_SCALE = BINS / 4.0  # a power of two: a pseudo-angle times it is exact
SHRINK = 0.01
"""How much of a cell each wall cell is shrunk by on every side."""
NEAR = 1.5
"""Wall cells nearer the node than this many cells cast no shadow."""
EPS = 1e-9
"""Pseudo-angle to spare at both ends of a wall cell's range of directions."""
SIDE = 8
"""Cells a side of the blocks of wall cells :func:`shade` passes over whole when none could draw (a divisor of 64)."""
_DE_BRUIJN = np.uint64(0x03F79D71B4CB0A89)
_LOWEST = np.zeros(64, np.int64)  # the index of a word's lowest set bit, by its de Bruijn product's top six bits
_LOWEST[[((1 << k) * 0x03F79D71B4CB0A89 % 2**64) >> 58 for k in range(64)]] = np.arange(64)
_ONES = np.uint64(0xFFFFFFFFFFFFFFFF)


@njit(cache=True, inline="always")
def pseudo_angle(dx, dy):  # pragma: no cover - numba
    """A stand-in for the direction of ``(dx, dy) != (0, 0)``, counter-clockwise from +x: in [0, 4], monotone."""
    if dy >= 0.0:
        if dx >= 0.0:
            return dy / (dx + dy)
        return 1.0 - dx / (dy - dx)
    if dx < 0.0:
        return 2.0 + dy / (dx + dy)
    return 3.0 + dx / (dx - dy)


@njit(cache=True, inline="always")
def _span(dx0, dx1, dy0, dy1):  # pragma: no cover - numba
    """The pseudo-angles ``(lo, hi)`` of the square ``[dx0, dx1] x [dy0, dy1]``'s corners, seen from the node.

    A square without the node spans less than a half turn; one across +x has its directions below 2 go on past 4.
    """
    a0 = pseudo_angle(dx0, dy0)
    a1 = pseudo_angle(dx1, dy0)
    a2 = pseudo_angle(dx0, dy1)
    a3 = pseudo_angle(dx1, dy1)
    lo = min(min(a0, a1), min(a2, a3))
    hi = max(max(a0, a1), max(a2, a3))
    if hi - lo > 2.0:
        a0 += 4.0 if a0 < 2.0 else 0.0
        a1 += 4.0 if a1 < 2.0 else 0.0
        a2 += 4.0 if a2 < 2.0 else 0.0
        a3 += 4.0 if a3 < 2.0 else 0.0
        lo = min(min(a0, a1), min(a2, a3))
        hi = max(max(a0, a1), max(a2, a3))
    return lo, hi


@njit(cache=True)
def shade(x, y, reach, bits, cols, ox, oy, res, out, lit):  # pragma: no cover - numba
    """Fill ``out`` and ``lit`` (:data:`BINS` floats each) with the shadows and the clear lines of ``(x, y)``.

    ``bits``: the map's bit grids (:func:`~amronet.engine.wall_bits.wall_bits`), ``cols`` its columns, ``(ox, oy)``
    and ``res`` its origin and cell size; the wall cells within ``reach`` count. ``out[b]``: the squared distance
    beyond which the lines in bin ``b``'s directions have crossed a wall cell (``inf``: none known). ``lit[b]``:
    the squared distance within which they are clear (see the module doc; read by :func:`clear` only).

    The wall cells go by blocks of :data:`SIDE` cells a side, in rings outwards from the node's block; a block
    that no cell of it could lower (every bin its directions reach is already at or below its nearest point,
    :func:`_hidden`) is passed over whole. Both are minima over the wall cells: the same numbers in any order.

    Returns:
        How many wall cells were drawn (the others were passed over by block).
    """
    out[:] = np.inf
    lit[:] = np.inf
    rows = bits.shape[1]
    if rows == 0 or cols == 0 or not (abs(x) + abs(y) + reach < 1e15):
        lit[:] = 0.0
        return 0
    if not (0 <= math.floor((y - oy) / res) < rows and 0 <= math.floor((x - ox) / res) < cols):
        lit[:] = 0.0  # the node outside the map, which the walk counts as wall: no line known clear
        lit[0] = -1.0  # (and no more to draw)
    r0 = max(int(math.floor((y - reach - oy) / res)), 0)
    r1 = min(int(math.floor((y + reach - oy) / res)), rows - 1)
    c0 = max(int(math.floor((x - reach - ox) / res)), 0)
    c1 = min(int(math.floor((x + reach - ox) / res)), cols - 1)
    if r0 > r1 or c0 > c1:
        return 0
    b0, b1, k0, k1 = r0 // SIDE, r1 // SIDE, c0 // SIDE, c1 // SIDE
    band = np.zeros((b1 - b0 + 1, (c1 >> 6) - (c0 >> 6) + 1), np.uint64)  # the wall bits of a band of SIDE rows
    for r in range(r0, r1 + 1):
        for w in range(c0 >> 6, (c1 >> 6) + 1):
            band[r // SIDE - b0, w - (c0 >> 6)] |= bits[0, _u(r), _u(w)]
    pb = min(max(int(math.floor(min(max((y - oy) / res, -1.0), rows + 1.0))) // SIDE, b0), b1)  # the node's block
    pk = min(max(int(math.floor(min(max((x - ox) / res, -1.0), cols + 1.0))) // SIDE, k0), k1)
    drawn = 0
    for ring in range(max(pb - b0, b1 - pb, pk - k0, k1 - pk) + 1):
        for bi in range(max(pb - ring, b0), min(pb + ring, b1) + 1):
            step = 1 if ring == 0 or bi == pb - ring or bi == pb + ring else 2 * ring  # the ring's sides only
            for bj in range(pk - ring, pk + ring + 1, step):
                if k0 <= bj <= k1:
                    ra, rb = max(bi * SIDE, r0), min(bi * SIDE + SIDE - 1, r1)
                    ca, cb = max(bj * SIDE, c0), min(bj * SIDE + SIDE - 1, c1)
                    w = ca >> 6
                    keep = (_ONES << _u(ca & 63)) & (_ONES >> _u(63 - (cb & 63)))  # the block's columns
                    if band[bi - b0, w - (c0 >> 6)] & keep == _u(0):
                        continue  # no wall cell
                    if _hidden(ox + ca * res + SHRINK * res - x - 2.0 * (SHRINK * res),
                               ox + (cb + 1) * res - SHRINK * res - x + 2.0 * (SHRINK * res),
                               oy + ra * res + SHRINK * res - y - 2.0 * (SHRINK * res),
                               oy + (rb + 1) * res - SHRINK * res - y + 2.0 * (SHRINK * res), res, reach, out, lit):
                        continue
                    drawn += _draw(x, y, reach, bits, ra, rb, w, keep, (ox, oy, res), out, lit)
    return drawn


@njit(cache=True)
def _hidden(dx0, dx1, dy0, dy1, res, reach, out, lit):  # pragma: no cover - numba
    """Whether no wall cell in the rectangle ``[dx0, dx1] x [dy0, dy1]`` (from the node) can lower ``out`` or ``lit``.

    The rectangle holds every wall cell's square grown by :data:`SHRINK` (the same operations as :func:`shade`'s,
    so its nearest point ``g2`` is no farther than any cell's, exactly). True when it is out of reach, or more than
    a block from the node and every bin its directions reach (:data:`EPS` to spare twice over) is already at or
    below ``g2``: a cell lowers a bin only to its own nearest (``lit``) or farthest (``out``) point.
    """
    gx = dx0 if dx0 > 0.0 else (-dx1 if dx1 < 0.0 else 0.0)
    gy = dy0 if dy0 > 0.0 else (-dy1 if dy1 < 0.0 else 0.0)
    g2 = gx * gx + gy * gy
    if g2 > reach * reach:
        return True
    if g2 <= (SIDE * res) * (SIDE * res):
        return False
    lo, hi = _span(dx0, dx1, dy0, dy1)
    for b in range(int(math.floor((lo - 2.0 * EPS) * _SCALE)), int(math.floor((hi + 2.0 * EPS) * _SCALE)) + 1):
        i = b % BINS
        if out[i] > g2 or lit[i] > g2:
            return False
    return True


@njit(cache=True)
def _draw(x, y, reach, bits, ra, rb, w, keep, grid, out, lit):  # pragma: no cover - numba
    """Draw the wall cells of rows ``ra..rb`` in word ``w``'s columns ``keep`` into ``out`` and ``lit``; how many.

    ``grid``: the map's ``(ox, oy, res)``.
    """
    ox, oy, res = grid
    near2 = (NEAR * res) * (NEAR * res)
    far2 = reach * reach
    s = SHRINK * res
    drawn = 0
    for r in range(ra, rb + 1):
        dy0 = oy + r * res + s - y
        dy1 = oy + (r + 1) * res - s - y
        gy = dy0 if dy0 > 0.0 else (-dy1 if dy1 < 0.0 else 0.0)
        fy = max(dy0 * dy0, dy1 * dy1)
        word = bits[0, _u(r), _u(w)] & keep
        while word != _u(0):  # the word's wall cells, lowest first
            low = word & (~word + _u(1))
            word ^= low
            c = w * 64 + _LOWEST[(low * _DE_BRUIJN) >> _u(58)]
            drawn += 1
            dx0 = ox + c * res + s - x
            dx1 = ox + (c + 1) * res - s - x
            gx = dx0 if dx0 > 0.0 else (-dx1 if dx1 < 0.0 else 0.0)
            gap2 = gx * gx + gy * gy
            if _light(dx0 - 2.0 * s, dx1 + 2.0 * s, dy0 - 2.0 * s, dy1 + 2.0 * s, far2, lit):
                lit[:] = 0.0  # the node is in a grown wall cell: no line known clear
                lit[0] = -1.0  # (and no more to draw)
            if gap2 < near2 or gap2 > far2:
                continue
            f2 = max(dx0 * dx0, dx1 * dx1) + fy
            lo, hi = _span(dx0, dx1, dy0, dy1)
            b0 = int(math.ceil((lo + EPS) * _SCALE))
            b1 = int(math.floor((hi - EPS) * _SCALE)) - 1  # bin b spans [b, b + 1) / _SCALE
            for b in range(b0, b1 + 1):
                i = b - BINS if b >= BINS else b
                if f2 < out[i]:
                    out[i] = f2
    return drawn


@njit(cache=True, inline="always")
def _light(dx0, dx1, dy0, dy1, far2, lit):  # pragma: no cover - numba
    """Lower ``lit`` to the square ``[dx0, dx1] x [dy0, dy1]``'s nearest point over its directions' bins.

    Returns True when the square holds the node (``lit`` untouched). Nothing is drawn for a square farther than
    ``sqrt(far2)`` (no segment within reach meets it), nor once ``lit[0] < 0``.
    """
    if lit[0] < 0.0:
        return False
    gx = dx0 if dx0 > 0.0 else (-dx1 if dx1 < 0.0 else 0.0)
    gy = dy0 if dy0 > 0.0 else (-dy1 if dy1 < 0.0 else 0.0)
    if gx == 0.0 and gy == 0.0:
        return True
    g2 = gx * gx + gy * gy
    if g2 > far2:
        return False
    lo, hi = _span(dx0, dx1, dy0, dy1)
    for b in range(int(math.floor((lo - EPS) * _SCALE)), int(math.floor((hi + EPS) * _SCALE)) + 1):
        i = b % BINS
        if g2 < lit[i]:
            lit[i] = g2
    return False


@njit(cache=True, inline="always")
def clear(lit, dx, dy, dd):  # pragma: no cover - numba
    """Whether the segment to ``(dx, dy) != (0, 0)`` from the node, ``dd`` its squared length, is clear of walls.

    ``lit``: :func:`shade`'s clear lines. True: the wall walk counts no wall on it.
    """
    b = int(pseudo_angle(dx, dy) * _SCALE)
    if b >= BINS:
        b = BINS - 1
    return dd < lit[b] * (1.0 - 1e-9)


@njit(cache=True, inline="always")
def behind(shadows, dx, dy, dd):  # pragma: no cover - numba
    """Whether the point ``(dx, dy)`` from the node, ``dd`` its squared distance, lies in :func:`shade`'s shadows."""
    b = int(pseudo_angle(dx, dy) * _SCALE)
    if b >= BINS:
        b = BINS - 1
    return dd > shadows[b] * (1.0 + 1e-9)


@njit(cache=True, inline="always")
def look(lit, shadows, dx, dy, dd, near2):  # pragma: no cover - numba
    """:func:`clear` and :func:`behind` of the point ``(dx, dy)`` from the node at once (one bin of directions).

    ``dd``: its squared distance; ``near2``: within it :func:`behind` is not asked. Returns 1 when the segment to
    the point is clear (``dd > 0``), else -1 when it lies in a shadow farther than ``near2``, else 0.
    """
    if not dd > 0.0:
        return 0
    b = int(pseudo_angle(dx, dy) * _SCALE)
    if b >= BINS:
        b = BINS - 1
    if dd < lit[b] * (1.0 - 1e-9):
        return 1
    if dd > near2 and dd > shadows[b] * (1.0 + 1e-9):
        return -1
    return 0


@njit(cache=True)
def dark(lit, shadows, dx0, dx1, dy0, dy1, near2):  # pragma: no cover - numba
    """Whether :func:`look` answers -1 for every point of the rectangle ``[dx0, dx1] x [dy0, dy1]`` from the node.

    True when the rectangle's nearest point is farther than ``near2`` and than the shadow of every bin its
    directions reach (one bin to spare on each side, for the rounding of :func:`pseudo_angle`), and no nearer than
    their clear lines: the squared distance of a point of it, computed as ``dx * dx + dy * dy`` from coordinates
    differences at least as large, is no smaller, so :func:`look` finds it in a shadow.
    """
    gx = dx0 if dx0 > 0.0 else (-dx1 if dx1 < 0.0 else 0.0)
    gy = dy0 if dy0 > 0.0 else (-dy1 if dy1 < 0.0 else 0.0)
    g2 = gx * gx + gy * gy
    if not g2 > near2:
        return False
    lo, hi = _span(dx0, dx1, dy0, dy1)
    for b in range(int(math.floor(lo * _SCALE)) - 1, int(math.floor(hi * _SCALE)) + 2):
        i = b % BINS
        if not g2 > shadows[i] * (1.0 + 1e-9) or g2 < lit[i] * (1.0 - 1e-9):
            return False
    return True
