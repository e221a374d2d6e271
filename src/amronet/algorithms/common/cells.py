"""A robot's local Voronoi cell, from what it hears and what it has seen, for many robots at once.

Robot ``i`` at ``p`` knows where the nodes it hears are (what they announce: these baselines are *location-aware*),
the obstacle points its own sensors hit (:class:`~amronet.algorithms.common.obstacle_memory.ObstacleMemory`) and the
area's bounding box (:class:`~amronet.algorithms.base.AreaKnowledge`, never the map). Its cell is the part of the
disk of radius ``R`` about ``p`` (a regular polygon of ``disk_vertices``; with no disk, ``R`` is so large that the
polygon holds the whole bounding box) that is

* nearer to ``p`` than to every node it hears: for a neighbour at ``q``, ``(x - p) . (q - p) <= |q - p|^2 / 2``
  (the bisector's half-plane; Voronoi's rule);
* on its side of every obstacle point ``o`` it remembers within ``R``: ``(x - p) . (o - p) <= |o - p|^2``, the line
  through ``o`` square to the robot's line of sight (what lies beyond a wall it has seen is not its free space);
* inside the area's bounding box.

All of them are half-planes, so the cell is convex: the disk clipped by each in turn, robot by robot in one
compiled pass (:func:`~amronet.algorithms.common.polygons.clip_one`). The cell comes back in coordinates relative to
``p``. With ``R`` at most half the distance within which a robot hears every node (``r_c / 2`` under the unit
disk), the cell is exactly the ``R``-limited Voronoi cell (Cortés, Martínez and Bullo 2005); with a larger ``R`` it
may be larger than the true cell where an unheard node is near (Wang, Cao and La Porta's caveat).
"""

from __future__ import annotations

import numba
import numpy as np

from amronet.algorithms.common.polygons import Polygons, clip_one, disk_overlap, regular
from amronet.engine.table import NeighbourTable

__all__ = ["covered_area", "farthest_point", "gains", "local_cells"]


@numba.njit(cache=True)
def _local_cells(robots, xy, generators, indptr, indices, points, filled, box, reach, disk):  # pragma: no cover
    """The cells of :func:`local_cells`: each robot's half-planes in order, the disk clipped by them.

    The polygons' width is the disk's vertices plus the most half-planes a robot has, as
    :func:`~amronet.algorithms.common.polygons.clip_each` would have them (the width decides the order in which
    :func:`~amronet.algorithms.common.polygons.area_centroid` adds up).
    """
    m, vertices = robots.shape[0], disk.shape[0]
    most = 0
    for r in range(m):  # room for the half-planes each may have
        i = robots[r]
        most = max(most, indptr[i + 1] - indptr[i] + filled[i] + 4)
    room = np.zeros((m, vertices + most, 2))
    count = np.zeros(m, dtype=np.int64)
    scratch = np.empty((vertices + most + 1, 2))
    cut = 2.0 * reach * reach
    planes = 0
    for r in range(m):
        i = robots[r]
        px, py = xy[i, 0], xy[i, 1]
        poly = room[r]
        for v in range(vertices):
            poly[v, 0] = disk[v, 0]
            poly[v, 1] = disk[v, 1]
        n, k = vertices, 0
        for e in range(indptr[i], indptr[i + 1]):  # the bisectors of the generators it hears
            j = indices[e]
            hx, hy = xy[j, 0] - px, xy[j, 1] - py
            half = 0.5 * (hx * hx + hy * hy)
            if generators[j] and half > 1e-24 and half < cut:  # |q - p| < 2 R cuts the disk
                k += 1
                if n > 0:
                    n = clip_one(poly, n, hx, hy, half, scratch)
        for f in range(filled[i]):  # the obstacle points it remembers within R
            ox, oy = points[i, f, 0] - px, points[i, f, 1] - py
            if np.hypot(ox, oy) < reach:
                k += 1
                if n > 0:
                    n = clip_one(poly, n, ox, oy, ox * ox + oy * oy, scratch)
        for side in range(4):  # the area's bounding box
            nx, ny = _BOX[side]
            c = box[1] - px if side == 0 else px - box[0] if side == 1 else box[3] - py if side == 2 else py - box[2]
            if c < reach:
                k += 1
                if n > 0:
                    n = clip_one(poly, n, nx, ny, c, scratch)
        count[r] = n
        planes = max(planes, k)
    return room[:, :vertices + planes].copy(), count


_BOX = ((1.0, 0.0), (-1.0, 0.0), (0.0, 1.0), (0.0, -1.0))
"""The outward normals of the bounding box's sides: ``x <= xmax``, ``-x <= -xmin``, ``y <= ymax``, ``-y <= -ymin``."""


def local_cells(robots: np.ndarray, xy: np.ndarray, generators: np.ndarray, table: NeighbourTable,
                seen: tuple[np.ndarray, np.ndarray], extent: tuple[float, float, float, float],
                reach: float, vertices: int) -> Polygons:
    """The local cells of ``robots`` ``(M,)``, relative to their positions (compiled, robot by robot).

    Args:
        robots: The robots whose cells are wanted.
        xy: Positions of every node (what the nodes announce).
        generators: Mask ``(N,)`` of the nodes that count as Voronoi generators when heard (routers and base
            nodes; not agents).
        table: The neighbour table (who each robot hears).
        seen: ``(points (N, C, 2), filled (N,))``: the obstacle points each node remembers, the first ``filled``
            of its row (:meth:`~amronet.algorithms.common.obstacle_memory.ObstacleMemory.remembered`); those
            within ``reach`` count.
        extent: ``(xmin, xmax, ymin, ymax)`` of the area.
        reach: ``R``, the radius of the bounding disk.
        vertices: Vertices of the polygon standing for the disk.
    """
    points, filled = seen
    xy_, count = _local_cells(np.asarray(robots, dtype=np.int64), xy, np.asarray(generators, dtype=np.bool_),
                              table.indptr, table.indices, points, np.asarray(filled, dtype=np.int64),
                              np.asarray(extent, dtype=np.float64), float(reach), regular(1, reach, vertices, 0).xy[0])
    return Polygons(xy_, count)


@numba.njit(cache=True)
def _farthest(xy, count, tie, far_out, point_out):  # pragma: no cover - numba
    """Each polygon's farthest vertex (see :func:`farthest_point`)."""
    for m in range(xy.shape[0]):
        n = count[m]
        if n == 0:
            continue
        far = -np.inf
        for v in range(n):
            far = max(far, np.hypot(xy[m, v, 0], xy[m, v, 1]))
        ux, uy, ties, first = 0.0, 0.0, 0, -1
        for v in range(n):
            d = np.hypot(xy[m, v, 0], xy[m, v, 1])
            if d >= far - tie:
                ux += xy[m, v, 0] / d
                uy += xy[m, v, 1] / d
                ties += 1
                first = v if first < 0 else first
        norm = np.hypot(ux, uy)
        far_out[m] = max(far, 0.0)
        if norm <= 1e-6 * max(ties, 1):
            point_out[m, 0], point_out[m, 1] = xy[m, first, 0], xy[m, first, 1]
        else:
            point_out[m, 0], point_out[m, 1] = ux / norm * far, uy / norm * far


def farthest_point(cells: Polygons, reach: float) -> tuple[np.ndarray, np.ndarray]:
    """Each cell's farthest vertex from its robot: ``(distance (M,), point (M, 2))``, relative to the robot.

    When several vertices are farthest (within ``1e-9 reach``: an arc of the bounding disk), the point at that
    distance in their mean direction stands for them (the middle of the arc), so that the choice does not hang on
    rounding; when their directions cancel out (a whole disk), the first of them. A cell without vertices: 0.
    """
    m = len(cells.count)
    far, point = np.zeros(m), np.zeros((m, 2))
    _farthest(cells.xy, cells.count.astype(np.int64), 1e-9 * reach, far, point)
    return far, point


def covered_area(cells: Polygons, centres: np.ndarray, radius: float, vertices: int) -> np.ndarray:
    """Area ``(M,)`` of each cell within ``radius`` of ``centres`` ``(M, 2)`` (all relative to the robot).

    The disk is the regular polygon of ``vertices`` inscribed in it (as the cell's bounding disk is).
    """
    return disk_overlap(cells, centres, radius, vertices)


def gains(cells: Polygons, move: np.ndarray, candidates: np.ndarray, r_s: float, vertices: int,
          min_gain: float) -> np.ndarray:
    """Which candidates' moves ``(M, 2)`` cover more of their cells than staying, by ``min_gain`` of the sensing disk.

    Wang, Cao and La Porta's movement adjustment: the coverage at the goal is taken with the robot's present cell.
    """
    out = np.zeros(len(move), dtype=bool)
    who = np.flatnonzero(candidates)
    if len(who) == 0:
        return out
    part = Polygons(cells.xy[who], cells.count[who])
    here = covered_area(part, np.zeros((len(who), 2)), r_s, vertices)
    there = covered_area(part, move[who], r_s, vertices)
    disk = 0.5 * vertices * r_s**2 * np.sin(2.0 * np.pi / vertices)
    out[who] = there - here > min_gain * disk
    return out
