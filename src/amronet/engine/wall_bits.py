"""The radio's wall walk on bit grids: the same counts as :func:`amronet.engine.walls.count_walls`, in less memory.

The walk of :mod:`amronet.engine.walls` reads a byte per cell (:func:`~amronet.engine.walls.wall_grid`'s wall cells)
and a float every few free cells (the safe jump), and the box test reads a summed-area table: 4-5 MB for a large
map, read all over by a step's links in no order, which a loaded machine's caches do not keep. Here the same
questions are asked of two bit grids of the map (:func:`wall_bits`, 1/32 of that: they stay in the core's cache):

* bit grid 0: the wall cells;
* bit grid 1: the free cells whose safe jump exceeds the walk's leap threshold (six cells), where the walk leaps.
  The float jump is read only there, to leap by it;
* the grids from 2 on: bit grid 0 transposed, column ``c`` in row ``c % rows`` of grid ``2 + c // rows`` (bit
  ``r % 64`` of its word ``r // 64``), where a column's words fit in a row's (none for a map taller than wide).

The walk (:func:`count_walls_bits`) takes the same steps, leaps at the same cells by the same distances and so
returns the same count as :func:`~amronet.engine.walls.count_walls`; it also stops as soon as the cells it has
left to walk hold no wall (:func:`box_free`). :func:`box_clear_bits` is :func:`~amronet.engine.walls.box_clear`
on the bit grid (the same rectangle; tested against each other).

Most segments are counted without the walk, line by line (:func:`count_walls_lines`): the cells a segment passes
through in one row (a shallow segment) or column (a steep one) are a run of consecutive cells, read as one window
of bits, whose runs of wall cells a popcount counts. That is the walk's count wherever the walk's rounding cannot
decide a cell: the segment's ends and its crossings of the lines are off the cell borders by a margin far above
that rounding (where they are not, the walk counts).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit
from numba import uint64 as _u  # unsigned indices: numba then skips its negative-index wraparound code

from amronet.engine.coverage_kernels import _popcount
from amronet.engine.walls import LEAP_CELLS, _widened, count_walls, wall_grid
from amronet.world.gridwalk import walk_start
from amronet.world.occupancy import OccupancyMap

__all__ = ["ROW_LEVELS", "box_clear_bits", "box_free", "count_walls_bits", "count_walls_lines", "wall_bits"]

_ONES = np.uint64(0xFFFFFFFFFFFFFFFF)

ROW_LEVELS = 3
"""The last grids: bit grid 0 with its rows OR'ed by ``2**k``, ``k = 1..ROW_LEVELS`` (see :func:`box_free`)."""


def wall_bits(omap: OccupancyMap) -> np.ndarray:
    """The map's bit grids (see the module doc), ``uint64 (2 + T, rows, ceil(cols / 64))``: computed once, cached.

    Bit ``c % 64`` of word ``[k, r, c // 64]`` is cell ``(r, c)`` of grid ``k`` (``k`` 0 or 1); the padding bits
    are 0. The ``T`` grids after them hold the wall cells transposed (see the module doc).
    """
    if "wall_bits" not in omap._cache:
        walls, jump = wall_grid(omap)
        leap = jump.astype(np.float64) > LEAP_CELLS * float(omap.resolution)  # the walk's own comparison
        rows, cols = walls.shape
        words = (cols + 63) // 64
        tall = (rows + 63) // 64  # words per column of the transposed grid
        extra = -(-cols // rows) if tall <= words else 0
        out = np.zeros((2 + extra + ROW_LEVELS, rows, words), np.uint64)
        for k, grid in enumerate((walls != 0, leap)):
            out[k] = _packed(grid)
        below = out[0]
        for k in range(1, ROW_LEVELS + 1):  # rows r..r + 2**k - 1: those of r..r + 2**(k-1) - 1 and the next as many
            half = 1 << (k - 1)
            level = out[1 + extra + k]
            level[:] = below
            level[:max(rows - half, 0)] |= below[half:]
            below = level
        if extra:
            flip = np.zeros((extra * rows, tall), np.uint64)
            flip[:cols] = _packed((walls != 0).T)
            out[2:2 + extra, :, :tall] = flip.reshape(extra, rows, tall)
        out.flags.writeable = False
        omap._cache["wall_bits"] = out
    return omap._cache["wall_bits"]


def _packed(grid: np.ndarray) -> np.ndarray:
    """A boolean ``(rows, cols)`` grid as ``uint64 (rows, ceil(cols / 64))`` words, cell ``c`` at bit ``c % 64``."""
    rows, cols = grid.shape
    words = (cols + 63) // 64
    padded = np.zeros((rows, words * 64), bool)
    padded[:, :cols] = grid
    weights = np.left_shift(np.uint64(1), np.arange(64, dtype=np.uint64))
    return (padded.reshape(rows, words, 64) * weights).sum(axis=2, dtype=np.uint64)


@njit(cache=True, inline="always")
def box_free(bits, cols, r0, r1, c0, c1):  # pragma: no cover - numba
    """Whether the cells of rows ``r0..r1`` and columns ``c0..c1`` (inclusive) are in the map and no wall.

    ``cols``: the map's columns (the bit grid's rows are padded to whole words).
    """
    if r0 < 0 or c0 < 0 or r1 >= bits.shape[1] or c1 >= cols:
        return False
    w0 = c0 >> 6
    w1 = c1 >> 6
    m0 = _ONES << _u(c0 & 63)
    m1 = _ONES >> _u(63 - (c1 & 63))
    span = r1 - r0 + 1
    if span <= 0:
        return True
    k = 0  # windows of 2**k rows, the last one ending at r1 (they may overlap: an OR does not mind)
    while k < ROW_LEVELS and (2 << k) <= span:
        k += 1
    grid = _u(0 if k == 0 else bits.shape[0] - 1 - ROW_LEVELS + k)
    size = 1 << k
    last = r1 - size + 1
    r = r0
    if w0 == w1:
        m = m0 & m1
        while True:
            if bits[grid, _u(r), _u(w0)] & m:
                return False
            if r == last:
                return True
            r = min(r + size, last)
    while True:
        if bits[grid, _u(r), _u(w0)] & m0 or bits[grid, _u(r), _u(w1)] & m1:
            return False
        for w in range(w0 + 1, w1):
            if bits[grid, _u(r), _u(w)]:
                return False
        if r == last:
            return True
        r = min(r + size, last)


@njit(cache=True, inline="always")
def box_clear_bits(bits, cols, ox, oy, res, x0, y0, x1, y1):  # pragma: no cover - numba
    """:func:`~amronet.engine.walls.box_clear` on the bit grid ``bits`` of a map of ``cols`` columns."""
    lo_u, hi_u, lo_v, hi_v = _widened(ox, oy, res, x0, y0, x1, y1)
    if not (lo_u >= 0.0 and lo_v >= 0.0 and hi_u < cols and hi_v < bits.shape[1]):
        return False  # outside the map (a wall), or not a number
    return box_free(bits, cols, int(lo_v), int(hi_v), int(lo_u), int(hi_u))


@njit(cache=True, inline="always")
def _bit(bits, k, r, c):  # pragma: no cover - numba
    """Cell ``(r, c)`` (in the map) of bit grid ``k``."""
    return (bits[k, _u(r), _u(c >> 6)] >> _u(c & 63)) & _u(1) != _u(0)


@njit(cache=True)
def count_walls_bits(bits, walls, jump, ox, oy, res, x0, y0, x1, y1, limit):  # pragma: no cover - numba
    """:func:`~amronet.engine.walls.count_walls` read from the bit grids ``bits`` (:func:`wall_bits`) of its map.

    ``walls`` and ``jump``: the map's :func:`~amronet.engine.walls.wall_grid`. A segment along an axis (which may lie
    on a cell border), a point or one with a coordinate that is not a number is handed to
    :func:`~amronet.engine.walls.count_walls` itself; most others are counted line by line
    (:func:`count_walls_lines`), and the walk below takes the rest.

    The same walk, step for step and leap for leap (``jump`` is read where bit grid 1 says the walk leaps), so the
    same count; on leaving a wall it stops when the rectangle of cells from the current cell to the far side of
    :func:`~amronet.engine.walls.box_clear`'s rectangle holds no wall: that rectangle holds every cell the walk
    still visits (the walk moves monotonically towards the far side; a leap may land a hair behind the current
    cell only in a cell within the safe jump, a free one), so the count is final.
    """
    rows = jump.shape[0]
    cols = jump.shape[1]
    if y0 == y1 or x0 == x1 or x0 != x0 or y0 != y0 or x1 != x1 or y1 != y1:  # rare: the plain walk
        return count_walls(walls, jump, ox, oy, res, x0, y0, x1, y1, limit)
    by_lines = count_walls_lines(bits, cols, ox, oy, res, x0, y0, x1, y1, limit)
    if by_lines >= 0:
        return by_lines
    length = math.sqrt((x1 - x0) * (x1 - x0) + (y1 - y0) * (y1 - y0))
    far = False  # whether the walk's rectangle (rows r_lo..r_hi, columns c_lo..c_hi) is known
    boxed = True
    r_lo = r_hi = c_lo = c_hi = 0
    count = 0
    inside = False
    t0 = 0.0  # where the current walk starts, as a fraction of the segment
    while True:
        r, c, r_end, c_end, step_r, step_c, t_x, t_y, dt_x, dt_y = walk_start(
            ox, oy, res, x0 + t0 * (x1 - x0), y0 + t0 * (y1 - y0), x1, y1)
        t_in = 0.0  # where the walk entered the current cell, as a fraction of the current walk
        since = 4  # free cells since the last look at the safe jump
        s = 0.0
        while True:
            if _u(r) < _u(rows) and _u(c) < _u(cols):  # in the map (unsigned: one comparison each)
                if _bit(bits, 0, r, c):
                    if not inside:
                        count += 1
                        if count > limit:
                            return count
                        inside = True
                else:
                    if inside and boxed:  # left a wall: is there any wall in the cells left to walk?
                        if not far:
                            far = True
                            lo_u, hi_u, lo_v, hi_v = _widened(ox, oy, res, x0, y0, x1, y1)
                            if abs(lo_u) + abs(hi_u) + abs(lo_v) + abs(hi_v) < 1e15:
                                r_lo = int(math.floor(lo_v))
                                r_hi = int(math.floor(hi_v))
                                c_lo = int(math.floor(lo_u))
                                c_hi = int(math.floor(hi_u))
                            else:
                                boxed = False  # too far off to index
                        # from the current cell to the far side of the rectangle
                        if boxed and box_free(bits, cols, r if y1 > y0 else min(r, r_lo),
                                              r if y1 < y0 else max(r, r_hi), c if x1 > x0 else min(c, c_lo),
                                              c if x1 < x0 else max(c, c_hi)):
                            return count
                    if inside or since >= 4:  # look for open space on leaving a wall and every few cells
                        since = 0
                        if _bit(bits, 1, r, c):
                            s = jump[r, c]
                            break  # open space: leap ahead from where the walk entered this cell
                    since += 1
                    inside = False
            elif not inside:
                count += 1
                if count > limit:
                    return count
                inside = True
            if r == r_end and c == c_end:
                return count
            if t_x < t_y:
                if t_x > 1.0:
                    return count
                t_in = t_x
                c += step_c
                t_x += dt_x
            else:
                if t_y > 1.0:
                    return count
                t_in = t_y
                r += step_r
                t_y += dt_y
        t0 = t0 + (1.0 - t0) * t_in + s / length
        if t0 >= 1.0:
            return count


@njit(cache=True, inline="always")
def _off_border(w, eps):  # pragma: no cover - numba
    """Whether the cell coordinate ``w`` is more than ``eps`` from a cell border."""
    f = w - math.floor(w)
    return f >= eps and f <= 1.0 - eps


@njit(cache=True)
def count_walls_lines(bits, cols, ox, oy, res, x0, y0, x1, y1, limit):  # pragma: no cover - numba
    """:func:`count_walls_bits`' count read line by line (see the module doc), or -1 where it does not decide.

    The segment's cells in cell coordinates ``(u, v)``: ``a`` along the lines and ``b`` across them (rows, ``a = u``,
    where the segment is shallow; columns of the transposed grid where it is steep, so the lines are the fewer).
    Line ``b`` holds the cells from where the segment enters it to where it leaves, one window of at most 64 bits
    (-1 for a segment with more cells in one line). Runs of wall cells: the window's set bits with no set bit
    before them, less one where the last cell of a line and the first of the next (the same ``a``: the walk steps
    across) are both walls. The count stops above ``limit`` as the walk's does.

    The walk's cells are these: it steps to the next cell over the border it reaches first, and rounding (of
    the order of 1e-16 of the coordinates, and of the segment's length in cells times that) could change its choice
    only where the segment passes that near a cell corner, or decide another first or last cell only where an end
    lies that near a border. Off by ``eps`` (at least 1e-6 of a cell) everywhere, the choice is the segment's own:
    the ends must be that far inside the map and off the borders, and so must every crossing of a line (-1
    otherwise). Leaps of the walk pass over free cells only, which change no count.
    """
    inv = 1.0 / res
    u0 = (x0 - ox) * inv
    v0 = (y0 - oy) * inv
    u1 = (x1 - ox) * inv
    v1 = (y1 - oy) * inv
    rows = bits.shape[1]
    size = abs(x0) + abs(y0) + abs(x1) + abs(y1) + abs(ox) + abs(oy)
    eps = 1e-6 + 1e-12 * size * inv + 1e-9 * (abs(u1 - u0) + abs(v1 - v0))
    if not (min(u0, u1) >= eps and min(v0, v1) >= eps and max(u0, u1) < cols - eps and max(v0, v1) < rows - eps
            and _off_border(u0, eps) and _off_border(v0, eps) and _off_border(u1, eps) and _off_border(v1, eps)):
        return -1
    words = bits.shape[2]
    if abs(u1 - u0) >= abs(v1 - v0) or bits.shape[0] < 3 + ROW_LEVELS:  # along the rows of grid 0
        a0, a1, b0, b1 = u0, u1, v0, v1
        transposed = False
    else:  # along the columns of the transposed grids
        a0, a1, b0, b1 = v0, v1, u0, u1
        transposed = True
    if b1 == b0 or not abs(a1 - a0) < 62.0 * abs(b1 - b0):  # at most 63 cells in one line
        return -1
    s = (a1 - a0) / (b1 - b0)
    line = int(b0)
    end = int(b1)
    step = 1 if b1 > b0 else -1
    lift = 1 if b1 > b0 else 0  # the border a line is left by, above its own index
    grid = 2 if transposed else 0  # where the line's words are: row `row` of grid `grid`
    row = line
    while row >= rows:  # (transposed grids only; no division)
        row -= rows
        grid += 1
    ca = int(a0)  # the first cell of the line (in the walk's order)
    count = 0
    last = _u(0)  # whether the last cell of the line before was a wall
    while True:
        if line == end:
            cb = int(a1)
        else:
            cross = a0 + ((line + lift) - b0) * s
            if not _off_border(cross, eps):
                return -1
            cb = int(cross)
        lo = min(ca, cb)
        at = lo >> 6
        shift = _u(lo & 63)
        x = (bits[_u(grid), _u(row), _u(at)] >> shift) | (
            (bits[_u(grid), _u(row), _u(min(at + 1, words - 1))] << (_u(63) - shift)) << _u(1))
        x &= _ONES >> _u(63 - (max(ca, cb) - lo))
        count += np.int64(_popcount(x & ~(x << _u(1)))) - np.int64((x >> _u(ca - lo)) & last)
        if count > limit:
            return limit + 1
        if line == end:
            return count
        last = (x >> _u(cb - lo)) & _u(1)
        ca = cb
        line += step
        row += step
        if row == rows:  # (transposed grids only)
            row = 0
            grid += 1
        elif row < 0:
            row = rows - 1
            grid -= 1
