"""Convex polygons of many robots at once: regular polygons, clipping by half-planes, area and centroid.

A batch of ``M`` convex polygons is one padded array of vertices ``(M, W, 2)`` (counter-clockwise, the first
``count[m]`` rows of polygon ``m`` valid) and the counts ``(M,)`` (:class:`Polygons`). Clipping by half-planes is
Sutherland–Hodgman's, compiled; a polygon clipped by ``k`` half-planes gains at most ``k`` vertices, so the width
``W`` is fixed once, when the batch is made. Area, centroid and the shapely geometries are array operations over all
polygons at once. This is the
local Voronoi cell's geometry (:mod:`amronet.algorithms.common.cells`): a disk cut by the bisectors of the
neighbours a robot hears, by what its sensors saw and by the area's bounding box.
"""

from __future__ import annotations

from typing import NamedTuple

import numba
import numpy as np
import shapely

__all__ = ["Polygons", "area_centroid", "clip_each", "regular", "to_shapely"]


class Polygons(NamedTuple):
    """``M`` convex polygons: vertices ``(M, W, 2)`` counter-clockwise, the first ``count[m]`` of row ``m`` valid."""

    xy: np.ndarray
    count: np.ndarray

    def valid(self) -> np.ndarray:
        """Mask ``(M, W)`` of the valid vertices."""
        return np.arange(self.xy.shape[1])[None, :] < self.count[:, None]

    def following(self) -> np.ndarray:
        """Index ``(M, W)`` of each vertex's successor along its polygon (0 after the last valid one)."""
        k = np.arange(self.xy.shape[1])[None, :]
        return np.where(k + 1 < self.count[:, None], k + 1, 0)


def regular(m: int, radius: float, vertices: int, width: int) -> Polygons:
    """``m`` copies of the regular ``vertices``-gon inscribed in the circle of ``radius`` about the origin.

    Args:
        m: How many polygons.
        radius: Circumradius (the vertices lie on the circle).
        vertices: Vertices of each polygon (at least 3).
        width: Room for vertices per polygon (at least ``vertices``; the clips to come add one each at most).
    """
    angles = np.arange(vertices) * (2.0 * np.pi / vertices)
    xy = np.zeros((m, max(width, vertices), 2))
    xy[:, :vertices, 0] = radius * np.cos(angles)
    xy[:, :vertices, 1] = radius * np.sin(angles)
    return Polygons(xy, np.full(m, vertices, dtype=np.int64))


@numba.njit(cache=True)
def _clip_each(xy, count, indptr, normal, offset, scratch):  # pragma: no cover - numba
    """Sutherland–Hodgman, polygon by polygon, half-plane by half-plane, in place (see :func:`clip_each`)."""
    for m in range(xy.shape[0]):
        n = count[m]
        for e in range(indptr[m], indptr[m + 1]):
            if n == 0:
                break
            nx, ny, c = normal[e, 0], normal[e, 1], offset[e]
            k = 0
            for v in range(n):
                w = v + 1 if v + 1 < n else 0
                ax, ay = xy[m, v, 0], xy[m, v, 1]
                bx, by = xy[m, w, 0], xy[m, w, 1]
                sa = ax * nx + ay * ny - c
                sb = bx * nx + by * ny - c
                if sa <= 0.0:
                    scratch[k, 0] = ax
                    scratch[k, 1] = ay
                    k += 1
                if (sa < 0.0 and sb > 0.0) or (sa > 0.0 and sb < 0.0):
                    t = sa / (sa - sb)
                    scratch[k, 0] = ax + t * (bx - ax)
                    scratch[k, 1] = ay + t * (by - ay)
                    k += 1
            for v in range(k):
                xy[m, v, 0] = scratch[v, 0]
                xy[m, v, 1] = scratch[v, 1]
            n = k
        count[m] = n


def clip_each(poly: Polygons, indptr: np.ndarray, normal: np.ndarray, offset: np.ndarray) -> Polygons:
    """Clip polygon ``m`` by every half-plane ``indptr[m]:indptr[m + 1]`` of ``normal`` ``(E, 2)``, ``offset`` ``(E,)``.

    Half-plane ``e`` keeps ``normal[e] . x <= offset[e]``; a polygon wholly outside one ends with count 0. A convex
    polygon clipped by ``k`` half-planes gains at most ``k`` vertices: ``poly``'s width must have room for them.
    Compiled, polygon by polygon (numpy passes over all polygons, one per rank of half-plane, took 50 ms a pass for
    3 000 robots).
    """
    xy, count = poly.xy.copy(), poly.count.astype(np.int64)
    scratch = np.empty((xy.shape[1] + 1, 2))
    _clip_each(xy, count, np.asarray(indptr, dtype=np.int64), np.ascontiguousarray(normal, dtype=np.float64),
               np.ascontiguousarray(offset, dtype=np.float64), scratch)
    return Polygons(xy, count)


def area_centroid(poly: Polygons) -> tuple[np.ndarray, np.ndarray]:
    """Area ``(M,)`` and centroid ``(M, 2)`` of every polygon (a polygon of no area: its vertices' mean, or 0)."""
    xy = poly.xy
    valid = poly.valid()
    nxt = np.take_along_axis(xy, poly.following()[:, :, None], axis=1)
    cross = np.where(valid, xy[:, :, 0] * nxt[:, :, 1] - nxt[:, :, 0] * xy[:, :, 1], 0.0)
    area = 0.5 * cross.sum(axis=1)
    moment = ((xy + nxt) * cross[:, :, None]).sum(axis=1)
    mean = (xy * valid[:, :, None]).sum(axis=1) / np.maximum(poly.count, 1)[:, None]
    flat = np.abs(area) <= 1e-15
    with np.errstate(invalid="ignore", divide="ignore"):
        centroid = np.where(flat[:, None], mean, moment / (6.0 * np.where(flat, 1.0, area))[:, None])
    return area, centroid


def to_shapely(poly: Polygons, shift: np.ndarray | None = None) -> np.ndarray:
    """The polygons as shapely geometries ``(M,)``, moved by ``shift`` ``(M, 2)`` (fewer than 3 vertices: empty)."""
    valid = poly.valid() & (poly.count[:, None] >= 3)
    xy = poly.xy if shift is None else poly.xy + shift[:, None, :]
    rows, _ = np.nonzero(valid)
    out = np.full(len(poly.count), shapely.Polygon(), dtype=object)
    if len(rows):
        have, rank = np.unique(rows, return_inverse=True)
        out[have] = shapely.polygons(shapely.linearrings(xy[valid], indices=rank))
    return out
