"""Walls crossed by the straight line between two points of an occupancy grid, in compiled code.

**The rule.** Occupied and unknown cells are *wall* cells (unknown space on a map is almost always solid or
outside the building: counting it as wall keeps links honest), and so is everything outside the map. The walls a
segment crosses are the **runs** of consecutive wall cells among the cells it passes through, in order: a thick
wall drawn as several cells is one wall, two walls with a room between them are two. The cells are those the
segment's interior passes through (the grid walk of :mod:`amronet.world.gridwalk`); a horizontal or vertical
segment lying exactly on a cell border (along a wall's face) is inside a wall only where the cells on *both*
sides are wall cells, so it crosses none when it runs along a face. A segment that only touches a wall cell at a
corner point is counted by the grid walk's tie rule (a measure-zero case; real positions never hit it exactly).

:func:`count_walls` stops as soon as the count exceeds ``limit`` (a link whose budget allows ``k`` walls needs no
more than ``k + 1`` counted), which keeps long walks through thick building cores short. Given the map's summed-area
table of wall cells (:func:`wall_sums`), :func:`box_clear` tells first whether the rectangle of cells between the
segment's two ends holds any wall cell (four reads): most links in a building run within one room or corridor, and
those need no walk. The walk never leaves that rectangle (widened by a hair for rounding), so where it holds no wall
the count is 0, the walk's own answer. The radio asks the same questions of bit grids of the map, which stay in the
processor's cache (:mod:`amronet.engine.wall_bits`).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit
from scipy import ndimage

from amronet.world.gridwalk import walk_next, walk_start
from amronet.world.occupancy import FREE, OccupancyMap

__all__ = ["LEAP_CELLS", "box_clear", "count_walls", "count_walls_many", "wall_grid", "wall_sums"]

LEAP_CELLS = 6.0
"""The walk leaps where a free cell's safe jump exceeds this many cells."""


def wall_grid(omap: OccupancyMap) -> tuple[np.ndarray, np.ndarray]:
    """The map's wall cells (``uint8``, occupied or unknown) and every cell's safe jump (m): computed once, cached.

    The safe jump of a free cell is a distance that a segment may travel from any point of the cell without
    meeting a wall cell: the distance between the cell's centre and the nearest wall cell's centre (Euclidean
    distance transform, the map's outside counting as wall) minus two half cell diagonals. Walks through open
    rooms leap by it instead of stepping cell by cell; the count is the same.
    """
    if "walls" not in omap._cache:
        grid = (omap.cells != FREE).astype(np.uint8)
        padded = np.pad(grid.astype(bool), 1, constant_values=True)
        edt = ndimage.distance_transform_edt(~padded)[1:-1, 1:-1] * omap.resolution
        jump = (np.clip(edt - math.sqrt(2.0) * omap.resolution, 0.0, None) * (1.0 - 1e-6)).astype(np.float32)
        for a in (grid, jump):
            a.flags.writeable = False
        omap._cache["walls"] = (grid, jump)
    return omap._cache["walls"]


def wall_sums(omap: OccupancyMap) -> np.ndarray:
    """The summed-area table of the map's wall cells (:func:`wall_grid`): computed once, cached.

    ``sums[i, j]`` (``int32``, ``(rows + 1, cols + 1)``, read-only) is the number of wall cells in rows ``< i`` and
    columns ``< j``, so any rectangle of cells takes four reads (:func:`box_clear`).
    """
    if "wall_sums" not in omap._cache:
        walls, _ = wall_grid(omap)
        sums = np.zeros((walls.shape[0] + 1, walls.shape[1] + 1), np.int32)
        np.cumsum(np.cumsum(walls, axis=0, dtype=np.int32), axis=1, out=sums[1:, 1:])
        sums.flags.writeable = False
        omap._cache["wall_sums"] = sums
    return omap._cache["wall_sums"]


@njit(cache=True, inline="always")
def box_clear(sums, ox, oy, res, x0, y0, x1, y1):  # pragma: no cover - numba
    """Whether every cell that the walk from ``(x0, y0)`` to ``(x1, y1)`` may visit is in the map and no wall.

    Those cells lie in the rectangle of cells between the two ends: the walk moves monotonically from the first
    end's cell towards the second's, and every cell it enters (also after a leap) is entered where the segment
    crosses a cell border at a parameter no greater than 1. Rounding can move a crossing by a hair (of the order of
    the last bit of the coordinates and of the origin, and of the squared length in cells times 1e-16): the
    rectangle is widened by a margin far above that, ``1e-9 + 1e-12 (|x0| + |y0| + |x1| + |y1| + |ox| + |oy|) / res
    + 1e-6 (|u1 - u0| + |v1 - v0|)`` cells for the ends' cell coordinates ``(u, v)``, so a segment whose end lies
    within it of a cell border is walked instead.

    Args:
        sums: The map's summed-area table of wall cells (:func:`wall_sums`).
        ox: The map's origin, x.
        oy: The map's origin, y.
        res: The map's cell size.
        x0: One end, x (world coordinates).
        y0: One end, y.
        x1: The other end, x.
        y1: The other end, y.
    """
    lo_u, hi_u, lo_v, hi_v = _widened(ox, oy, res, x0, y0, x1, y1)
    if not (lo_u >= 0.0 and lo_v >= 0.0 and hi_u < sums.shape[1] - 1 and hi_v < sums.shape[0] - 1):
        return False  # outside the map (a wall), or not a number
    c0 = np.uint64(lo_u)  # non-negative: truncation is the floor (unsigned: no wraparound code in the reads)
    c1 = np.uint64(hi_u) + np.uint64(1)
    r0 = np.uint64(lo_v)
    r1 = np.uint64(hi_v) + np.uint64(1)
    return sums[r1, c1] - sums[r0, c1] - sums[r1, c0] + sums[r0, c0] == 0


@njit(cache=True, inline="always")
def _widened(ox, oy, res, x0, y0, x1, y1):  # pragma: no cover - numba
    """The rectangle ``(lo_u, hi_u, lo_v, hi_v)``, in cell coordinates, that holds every cell the walk may visit.

    The rectangle between the ends' cell coordinates ``(u, v)``, widened by the margin of :func:`box_clear`.
    """
    inv = 1.0 / res
    u0 = (x0 - ox) * inv
    v0 = (y0 - oy) * inv
    u1 = (x1 - ox) * inv
    v1 = (y1 - oy) * inv
    du = abs(u1 - u0)
    dv = abs(v1 - v0)
    size = abs(x0) + abs(y0) + abs(x1) + abs(y1) + abs(ox) + abs(oy)
    slack = 1e-9 + 1e-12 * size * inv + 1e-6 * (du + dv)
    return min(u0, u1) - slack, max(u0, u1) + slack, min(v0, v1) - slack, max(v0, v1) + slack


@njit(cache=True, inline="always")
def _wall(walls, r, c):  # pragma: no cover - numba
    if r < 0 or c < 0 or r >= walls.shape[0] or c >= walls.shape[1]:
        return True
    return walls[r, c] != 0


@njit(cache=True)
def _count_on_border(walls, ox, oy, res, x0, y0, x1, y1, limit, on_row_border):  # pragma: no cover - numba
    """:func:`count_walls` for a segment lying on a cell border: wall where the cells on both sides are walls."""
    r, c, r_end, c_end, step_r, step_c, t_x, t_y, dt_x, dt_y = walk_start(ox, oy, res, x0, y0, x1, y1)
    count = 0
    inside = False
    while True:
        if on_row_border:
            w = _wall(walls, r, c) and _wall(walls, r - 1, c)
        else:
            w = _wall(walls, r, c) and _wall(walls, r, c - 1)
        if w and not inside:
            count += 1
            if count > limit:
                return count
        inside = w
        if r == r_end and c == c_end:
            return count
        r, c, t_x, t_y, past_end = walk_next(r, c, step_r, step_c, t_x, t_y, dt_x, dt_y)
        if past_end:
            return count


@njit(cache=True)
def count_walls(walls, jump, ox, oy, res, x0, y0, x1, y1, limit):  # pragma: no cover - numba
    """Walls (runs of wall cells) crossed by the segment ``(x0, y0) -> (x1, y1)``; stops once above ``limit``.

    The walk steps cell by cell like :func:`~amronet.world.gridwalk.walk_next` (written out here: this loop is the
    radio's hot path) and leaps through open space by the safe jumps. Where :func:`box_clear` is true it returns 0
    (ask that first: four reads instead of a walk).

    Args:
        walls: The wall grid (:func:`wall_grid`), row 0 at the bottom.
        jump: The safe jumps (:func:`wall_grid`).
        ox: The map's origin, x.
        oy: The map's origin, y.
        res: The map's cell size.
        x0: Start of the segment, x (world coordinates).
        y0: Start, y.
        x1: End, x.
        y1: End, y.
        limit: Stop counting once the count exceeds this (pass a large number for the full count).
    """
    if y0 == y1:
        v = (y0 - oy) / res
        if v == math.floor(v):
            return _count_on_border(walls, ox, oy, res, x0, y0, x1, y1, limit, np.bool_(True))
    if x0 == x1:
        v = (x0 - ox) / res
        if v == math.floor(v):
            return _count_on_border(walls, ox, oy, res, x0, y0, x1, y1, limit, np.bool_(False))
    length = math.sqrt((x1 - x0) * (x1 - x0) + (y1 - y0) * (y1 - y0))
    if length == 0.0:  # a point: inside a wall or not
        return 1 if _wall(walls, int(math.floor((y0 - oy) / res)), int(math.floor((x0 - ox) / res))) else 0
    leap_min = LEAP_CELLS * res
    rows = walls.shape[0]
    cols = walls.shape[1]
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
            if 0 <= r < rows and 0 <= c < cols:
                if walls[r, c] != 0:
                    if not inside:
                        count += 1
                        if count > limit:
                            return count
                        inside = True
                else:
                    if inside or since >= 4:  # look for open space on leaving a wall and every few cells
                        since = 0
                        s = jump[r, c]
                        if s > leap_min:
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


@njit(cache=True)
def count_walls_many(walls, jump, ox, oy, res, a, b, limit):  # pragma: no cover - numba
    """:func:`count_walls` for segments ``a[k] -> b[k]`` (arrays ``(M, 2)``), each with its own ``limit[k]``."""
    out = np.empty(a.shape[0], np.int64)
    for k in range(a.shape[0]):
        out[k] = count_walls(walls, jump, ox, oy, res, a[k, 0], a[k, 1], b[k, 0], b[k, 1], limit[k])
    return out
