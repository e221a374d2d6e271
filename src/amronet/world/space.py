"""Free space of a map: the region robots can reach from given points, and clearance to the nearest wall.

Both functions treat ``OCCUPIED`` and ``UNKNOWN`` cells alike as blocked, and everything outside the map's
rectangle as blocked too.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit
from scipy import ndimage

from amronet.errors import MapError
from amronet.world.gridwalk import walk_next as _walk_next
from amronet.world.gridwalk import walk_start as _walk_start
from amronet.world.occupancy import OccupancyMap

__all__ = ["CLEARANCE_SLACK", "clearance", "path_is_clear", "reachable_free", "wall_distance"]

CLEARANCE_SLACK: float = (math.sqrt(2.0) - 1.0) / 2.0
"""How far (in cells) :func:`clearance` may overestimate the exact distance from a cell's centre to the nearest
blocked cell's square; any point of the cell is within another ``sqrt(2) / 2`` cells of its centre."""

_CROSS = ndimage.generate_binary_structure(2, 1)
"""4-connectivity: cells touching only at a corner are not neighbours, so diagonal walls do not leak."""


def reachable_free(omap: OccupancyMap, seeds_xy: np.ndarray) -> np.ndarray:
    """Return the free cells 4-connected to the cells holding the seed points.

    Connectivity is 4-neighbour (a cross), so a wall of one-pixel-thick diagonal steps is closed. Only cells
    of the map count: free space beyond the map's edge is never reached, even when the map's outermost cells
    are free.

    Args:
        omap: The map.
        seeds_xy: World points ``(x, y)``, shape ``(2,)`` or ``(n, 2)``; each must lie in a free cell.
            With no seed at all the result is all ``False``.

    Returns:
        Boolean array of the map's shape, ``True`` for the free cells reachable from at least one seed.

    Raises:
        MapError: A seed lies outside the map or in an occupied or unknown cell; the field is
            ``seeds[i]``.
    """
    seeds = np.asarray(seeds_xy, dtype=float).reshape(-1, 2)
    free = omap.free
    if len(seeds) == 0:
        return np.zeros(free.shape, dtype=bool)
    rows, cols = omap.world_to_cell(seeds)
    inside = omap.inside(seeds)
    for i, (x, y) in enumerate(seeds):
        if not inside[i]:
            raise MapError(
                f"seeds[{i}]",
                f"point ({x:g}, {y:g}) lies outside map '{omap.name}' (extent {_fmt(omap.extent)}); "
                "move it into free space",
            )
        if not free[rows[i], cols[i]]:
            raise MapError(
                f"seeds[{i}]",
                f"point ({x:g}, {y:g}) lies in a blocked cell (row {rows[i]}, col {cols[i]}) of map "
                f"'{omap.name}'; move it into free space",
            )
    labels, count = _free_components(omap)
    wanted = np.zeros(count + 1, dtype=bool)  # a lookup by label: np.isin's sort of every cell costs ten times more
    wanted[labels[rows, cols]] = True
    return wanted[labels]


def _free_components(omap: OccupancyMap) -> tuple[np.ndarray, int]:
    """The 4-connected components of the map's free cells (0: not free) and their count, cached in ``omap._cache``."""
    if "free_components" not in omap._cache:
        labels, count = ndimage.label(omap.free, structure=_CROSS)
        labels.flags.writeable = False
        omap._cache["free_components"] = (labels, int(count))
    return omap._cache["free_components"]


def clearance(omap: OccupancyMap) -> np.ndarray:
    """Return each cell's distance in metres to the nearest blocked cell (occupied, unknown or off the map).

    Convention: the Euclidean distance between the cell's centre and the nearest blocked cell's centre,
    minus half a cell (``0.5 * resolution``), clipped at 0. So blocked cells have clearance 0 and a free cell
    next to a wall (or to the map's edge) has ``0.5 * resolution``: the distance from its centre to the wall's
    face. When the nearest blocked cell lies straight along a row or column this is the exact distance to
    that cell's nearest point; otherwise it overestimates it by at most ``(sqrt(2) - 1) / 2 * resolution``
    (about 0.21 cells).

    The result is computed once per map, cached in ``omap._cache`` and returned read-only.

    Args:
        omap: The map.

    Returns:
        ``float`` array of the map's shape, in metres.
    """
    if "clearance" not in omap._cache:
        padded = np.pad(omap.blocked, 1, constant_values=True)
        dist = ndimage.distance_transform_edt(~padded)[1:-1, 1:-1] * omap.resolution
        clear = np.clip(dist - 0.5 * omap.resolution, 0.0, None)
        clear.flags.writeable = False
        omap._cache["clearance"] = clear
    return omap._cache["clearance"]


# --------------------------------------------------------------------------------------------------------
# exact distances to the blocked squares (compiled)
# --------------------------------------------------------------------------------------------------------


@njit(cache=True, inline="always")
def _point_square_gap(px, py, sx, sy, res):  # pragma: no cover - numba
    """Distance from the point ``(px, py)`` to the square ``[sx, sx + res] x [sy, sy + res]`` (0 inside)."""
    dx = sx - px if px < sx else (px - sx - res if px > sx + res else 0.0)
    dy = sy - py if py < sy else (py - sy - res if py > sy + res else 0.0)
    return math.sqrt(dx * dx + dy * dy)


@njit(cache=True, inline="always")
def _point_segment_gap(px, py, ax, ay, bx, by):  # pragma: no cover - numba
    vx = bx - ax
    vy = by - ay
    ll = vx * vx + vy * vy
    t = 0.0 if ll == 0.0 else min(max(((px - ax) * vx + (py - ay) * vy) / ll, 0.0), 1.0)
    dx = ax + t * vx - px
    dy = ay + t * vy - py
    return math.sqrt(dx * dx + dy * dy)


@njit(cache=True)
def _segment_square_gap(ax, ay, bx, by, sx, sy, res):  # pragma: no cover - numba
    """Distance from the segment ``a -> b`` to the square at ``(sx, sy)`` of side ``res`` (0 when they meet).

    Two disjoint convex sets are closest at a vertex of one of them: the segment's ends or the square's corners.
    """
    # Liang-Barsky: does the segment meet the closed square?
    lo = 0.0
    hi = 1.0
    meets = True
    for p, d, a, b in ((ax, bx - ax, sx, sx + res), (ay, by - ay, sy, sy + res)):
        if d == 0.0:
            if p < a or p > b:
                meets = False
        else:
            t0 = (a - p) / d
            t1 = (b - p) / d
            if t0 > t1:
                t0, t1 = t1, t0
            lo = max(lo, t0)
            hi = min(hi, t1)
    if meets and lo <= hi:
        return 0.0
    g = min(_point_square_gap(ax, ay, sx, sy, res), _point_square_gap(bx, by, sx, sy, res))
    for cx, cy in ((sx, sy), (sx + res, sy), (sx, sy + res), (sx + res, sy + res)):
        g = min(g, _point_segment_gap(cx, cy, ax, ay, bx, by))
    return g


@njit(cache=True, inline="always")
def _blocked(blocked, r, c):  # pragma: no cover - numba
    return r < 0 or c < 0 or r >= blocked.shape[0] or c >= blocked.shape[1] or blocked[r, c] != 0


@njit(cache=True)
def _wall_distance(blocked, clear, ox, oy, res, x, y, cap):  # pragma: no cover - numba
    """Exact distance from ``(x, y)`` to the nearest blocked square (outside the map counts), up to ``cap``."""
    r0 = int(math.floor((y - oy) / res))
    c0 = int(math.floor((x - ox) / res))
    if _blocked(blocked, r0, c0):
        return 0.0
    # the nearest square is within clear + the slack + half a diagonal of the point
    reach = min(clear[r0, c0] + (CLEARANCE_SLACK + 0.75) * res, cap)
    k = int(math.ceil(reach / res)) + 1
    best = reach
    for r in range(r0 - k, r0 + k + 1):
        for c in range(c0 - k, c0 + k + 1):
            if _blocked(blocked, r, c):
                best = min(best, _point_square_gap(x, y, ox + c * res, oy + r * res, res))
    return best


def wall_distance(omap: OccupancyMap, xy: np.ndarray, cap: float = math.inf) -> np.ndarray:
    """Exact distance from each point to the nearest blocked cell's square (occupied, unknown or off the map).

    Unlike :func:`clearance` (a per-cell value measured from the cell's centre), this is the true Euclidean
    distance from the point itself to the blocked region, 0 for points inside it.

    Args:
        omap: The map.
        xy: Points ``(..., 2)``.
        cap: Distances above this are reported as ``cap`` (bounds the search).

    Returns:
        Distances in metres, shape ``xy.shape[:-1]``.
    """
    xy = np.asarray(xy, dtype=float)
    flat = xy.reshape(-1, 2)
    out = np.empty(len(flat))
    blocked = omap.blocked.view(np.uint8)
    clear = clearance(omap)
    for k in range(len(flat)):
        out[k] = _wall_distance(blocked, clear, float(omap.origin[0]), float(omap.origin[1]),
                                float(omap.resolution), flat[k, 0], flat[k, 1], float(cap))
    return out.reshape(xy.shape[:-1])


@njit(cache=True)
def path_is_clear(blocked, clear, ox, oy, res, x0, y0, x1, y1, radius):  # pragma: no cover - numba
    """Whether a disc of ``radius`` moving from ``(x0, y0)`` to ``(x1, y1)`` stays clear of every blocked square.

    Exact: the swept disc meets a blocked square exactly when the segment's distance to it is below ``radius``.
    A square the disc overlaps already at the start (a body placed closer than its radius) only forbids moves
    that end closer to it, so such a robot can still back away. Cells whose :func:`clearance` rules out any
    square within reach are skipped; the others are checked square by square.
    """
    k = int(math.ceil(radius / res)) + 1
    margin = radius + (CLEARANCE_SLACK + 0.75) * res
    rows, cols = clear.shape
    r, c, r_end, c_end, step_r, step_c, t_x, t_y, dt_x, dt_y = _walk_start(ox, oy, res, x0, y0, x1, y1)
    for _ in range(4 * (rows + cols) + 4):
        if r < 0 or r >= rows or c < 0 or c >= cols or blocked[r, c] != 0:
            return False
        if clear[r, c] < margin:
            for rr in range(r - k, r + k + 1):
                for cc in range(c - k, c + k + 1):
                    if not _blocked(blocked, rr, cc):
                        continue
                    sx = ox + cc * res
                    sy = oy + rr * res
                    if _segment_square_gap(x0, y0, x1, y1, sx, sy, res) >= radius:
                        continue
                    start = _point_square_gap(x0, y0, sx, sy, res)
                    if start >= radius or _point_square_gap(x1, y1, sx, sy, res) < start:
                        return False
        if r == r_end and c == c_end:
            return True
        r, c, t_x, t_y, past_end = _walk_next(r, c, step_r, step_c, t_x, t_y, dt_x, dt_y)
        if past_end:
            return True
    return True


def _fmt(extent: tuple[float, float, float, float]) -> str:
    """Format a map extent ``(xmin, xmax, ymin, ymax)`` for an error message."""
    xmin, xmax, ymin, ymax = extent
    return f"x {xmin:g}..{xmax:g}, y {ymin:g}..{ymax:g}"
