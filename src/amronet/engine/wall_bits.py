"""The radio's wall walk on bit grids: the same counts as :func:`amronet.engine.walls.count_walls`, in less memory.

The walk of :mod:`amronet.engine.walls` reads a byte per cell (:func:`~amronet.engine.walls.wall_grid`'s wall cells)
and a float every few free cells (the safe jump), and the box test reads a summed-area table: 4-5 MB for a large
map, read all over by a step's links in no order, which a loaded machine's caches do not keep. Here the same
questions are asked of two bit grids of the map (:func:`wall_bits`, 1/32 of that: they stay in the core's cache):

* bit grid 0: the wall cells;
* bit grid 1: the free cells whose safe jump exceeds the walk's leap threshold (six cells), where the walk leaps.
  The float jump is read only there, to leap by it.

The walk (:func:`count_walls_bits`) takes the same steps, leaps at the same cells by the same distances and so
returns the same count as :func:`~amronet.engine.walls.count_walls`; it also stops as soon as the cells it has
left to walk hold no wall (:func:`box_free`). :func:`box_clear_bits` is :func:`~amronet.engine.walls.box_clear`
on the bit grid (the same rectangle; tested against each other).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit
from numba import uint64 as _u  # unsigned indices: numba then skips its negative-index wraparound code

from amronet.engine.walls import LEAP_CELLS, _widened, count_walls, wall_grid
from amronet.world.gridwalk import walk_start
from amronet.world.occupancy import OccupancyMap

__all__ = ["box_clear_bits", "box_free", "count_walls_bits", "wall_bits"]

_ONES = np.uint64(0xFFFFFFFFFFFFFFFF)


def wall_bits(omap: OccupancyMap) -> np.ndarray:
    """The map's two bit grids (see the module doc), ``uint64 (2, rows, ceil(cols / 64))``: computed once, cached.

    Bit ``c % 64`` of word ``[k, r, c // 64]`` is cell ``(r, c)`` of grid ``k``; the padding bits are 0.
    """
    if "wall_bits" not in omap._cache:
        walls, jump = wall_grid(omap)
        leap = jump.astype(np.float64) > LEAP_CELLS * float(omap.resolution)  # the walk's own comparison
        rows, cols = walls.shape
        words = (cols + 63) // 64
        out = np.zeros((2, rows, words), np.uint64)
        for k, grid in enumerate((walls != 0, leap)):
            padded = np.zeros((rows, words * 64), bool)
            padded[:, :cols] = grid
            weights = np.left_shift(np.uint64(1), np.arange(64, dtype=np.uint64))
            out[k] = (padded.reshape(rows, words, 64) * weights).sum(axis=2, dtype=np.uint64)
        out.flags.writeable = False
        omap._cache["wall_bits"] = out
    return omap._cache["wall_bits"]


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
    if w0 == w1:
        m = m0 & m1
        for r in range(r0, r1 + 1):
            if bits[0, _u(r), _u(w0)] & m:
                return False
        return True
    for r in range(r0, r1 + 1):
        if bits[0, _u(r), _u(w0)] & m0 or bits[0, _u(r), _u(w1)] & m1:
            return False
        for w in range(w0 + 1, w1):
            if bits[0, _u(r), _u(w)]:
                return False
    return True


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
    :func:`~amronet.engine.walls.count_walls` itself.

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
