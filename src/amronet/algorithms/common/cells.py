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

All of them are half-planes, so the cell is convex and every robot's is clipped in the same passes of array
operations (:func:`~amronet.algorithms.common.polygons.clip_each`). The cell comes back in coordinates relative to
``p``. With ``R`` at most half the distance within which a robot hears every node (``r_c / 2`` under the unit
disk), the cell is exactly the ``R``-limited Voronoi cell (Cortés, Martínez and Bullo 2005); with a larger ``R`` it
may be larger than the true cell where an unheard node is near (Wang, Cao and La Porta's caveat).
"""

from __future__ import annotations

import numpy as np
import shapely

from amronet.algorithms.common.polygons import Polygons, clip_each, regular, to_shapely
from amronet.engine.table import NeighbourTable

__all__ = ["covered_area", "farthest_point", "gains", "local_cells"]


def local_cells(robots: np.ndarray, xy: np.ndarray, generators: np.ndarray, table: NeighbourTable,
                obstacles: tuple[np.ndarray, np.ndarray], extent: tuple[float, float, float, float],
                reach: float, vertices: int) -> Polygons:
    """The local cells of ``robots`` ``(M,)``, relative to their positions.

    Args:
        robots: The robots whose cells are wanted.
        xy: Positions of every node (what the nodes announce).
        generators: Mask ``(N,)`` of the nodes that count as Voronoi generators when heard (routers and base
            nodes; not agents).
        table: The neighbour table (who each robot hears).
        obstacles: ``(rank in robots (K,), offset from the robot (K, 2))``: the obstacle points each remembers.
        extent: ``(xmin, xmax, ymin, ymax)`` of the area.
        reach: ``R``, the radius of the bounding disk.
        vertices: Vertices of the polygon standing for the disk.
    """
    m = len(robots)
    degree = np.diff(table.indptr)[robots]
    rank = np.repeat(np.arange(m), degree)
    entry = np.repeat(table.indptr[robots] - np.cumsum(degree) + degree, degree) + np.arange(len(rank))
    other = table.indices[entry]
    heard = xy[other] - xy[robots][rank]
    half = 0.5 * np.einsum("ij,ij->i", heard, heard)
    useful = generators[other] & (half > 1e-24) & (half < 2.0 * reach * reach)  # |q - p| < 2 R cuts the disk
    seen_rank, seen = obstacles
    seen_sq = np.einsum("ij,ij->i", seen, seen)
    xmin, xmax, ymin, ymax = extent
    p = xy[robots]
    box_normal = np.array([[1.0, 0.0], [-1.0, 0.0], [0.0, 1.0], [0.0, -1.0]])
    box_offset = np.stack([xmax - p[:, 0], p[:, 0] - xmin, ymax - p[:, 1], p[:, 1] - ymin], axis=1)
    box_rank, box_side = np.nonzero(box_offset < reach)
    ranks = np.concatenate([rank[useful], seen_rank, box_rank])
    normal = np.concatenate([heard[useful], seen, box_normal[box_side]])
    offset = np.concatenate([half[useful], seen_sq, box_offset[box_rank, box_side]])
    order = np.argsort(ranks, kind="stable")
    indptr = np.zeros(m + 1, dtype=np.int64)
    np.cumsum(np.bincount(ranks, minlength=m), out=indptr[1:])
    width = vertices + int(np.diff(indptr).max(initial=0))
    return clip_each(regular(m, reach, vertices, width), indptr, normal[order], offset[order])


def farthest_point(cells: Polygons, reach: float) -> tuple[np.ndarray, np.ndarray]:
    """Each cell's farthest vertex from its robot: ``(distance (M,), point (M, 2))``, relative to the robot.

    When several vertices are farthest (within ``1e-9 reach``: an arc of the bounding disk), the point at that
    distance in their mean direction stands for them (the middle of the arc), so that the choice does not hang on
    rounding; when their directions cancel out (a whole disk), the first of them.
    """
    xy, valid = cells.xy, cells.valid()
    dist = np.where(valid, np.hypot(xy[:, :, 0], xy[:, :, 1]), -np.inf)
    far = dist.max(axis=1, initial=-np.inf)
    ties = valid & (dist >= far[:, None] - 1e-9 * reach)
    with np.errstate(invalid="ignore", divide="ignore"):
        unit = np.where(ties[:, :, None], xy / dist[:, :, None], 0.0).sum(axis=1)
    norm = np.hypot(unit[:, 0], unit[:, 1])
    first = np.take_along_axis(xy, np.argmax(ties, axis=1)[:, None, None], axis=1)[:, 0]
    cancel = norm <= 1e-6 * np.maximum(ties.sum(axis=1), 1)
    point = np.where(cancel[:, None], first, unit / np.where(cancel, 1.0, norm)[:, None] * far[:, None])
    return np.maximum(far, 0.0), np.where((cells.count > 0)[:, None], point, 0.0)


def covered_area(cells: Polygons, centres: np.ndarray, radius: float, vertices: int) -> np.ndarray:
    """Area ``(M,)`` of each cell within ``radius`` of ``centres`` ``(M, 2)`` (all relative to the robot).

    The disk is the regular polygon of ``vertices`` inscribed in it (as the cell's bounding disk is).
    """
    disks = regular(len(centres), radius, vertices, vertices)
    return shapely.area(shapely.intersection(to_shapely(cells), to_shapely(disks, shift=centres)))


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
