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
more than ``k + 1`` counted), which keeps long walks through thick building cores short.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit
from scipy import ndimage

from amronet.world.gridwalk import walk_next, walk_start
from amronet.world.occupancy import FREE, OccupancyMap

__all__ = ["count_walls", "count_walls_many", "wall_grid"]


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
    radio's hot path) and leaps through open space by the safe jumps.

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
    leap_min = 6.0 * res
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
