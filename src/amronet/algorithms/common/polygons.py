"""Convex polygons of many robots at once: regular polygons, clipping by half-planes, area and centroid.

A batch of ``M`` convex polygons is one padded array of vertices ``(M, W, 2)`` (counter-clockwise, the first
``count[m]`` rows of polygon ``m`` valid) and the counts ``(M,)`` (:class:`Polygons`). Clipping by half-planes is
Sutherland–Hodgman's, compiled (:func:`clip_one`, the one clip every kernel here uses); a polygon clipped by ``k``
half-planes gains at most ``k`` vertices, so the width ``W`` is fixed once, when the batch is made. Area and
centroid, and the area within a disk, are compiled too, polygon by polygon; shapely's geometries
(:func:`to_shapely`) are for the tests that check them. This is the local Voronoi cell's geometry
(:mod:`amronet.algorithms.common.cells`): a disk cut by the bisectors of the neighbours a robot hears, by what its
sensors saw and by the area's bounding box.
"""

from __future__ import annotations

from typing import NamedTuple

import numba
import numpy as np
import shapely

__all__ = ["Polygons", "area_centroid", "clip_each", "clip_one", "disk_overlap", "regular", "to_shapely"]


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
def clip_one(poly, n, nx, ny, c, scratch):  # pragma: no cover - numba
    """Clip the first ``n`` vertices of ``poly`` ``(W, 2)`` by ``nx x + ny y <= c`` in place; the new count.

    Sutherland–Hodgman for one half-plane (``scratch``: room for ``n + 1`` vertices); every compiled clip here is
    this one, so the same polygon clipped by the same half-plane gives the same vertices bit for bit.
    """
    k = 0
    for v in range(n):
        w = v + 1 if v + 1 < n else 0
        ax, ay = poly[v, 0], poly[v, 1]
        bx, by = poly[w, 0], poly[w, 1]
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
        poly[v, 0] = scratch[v, 0]
        poly[v, 1] = scratch[v, 1]
    return k


@numba.njit(cache=True)
def _clip_each(xy, count, indptr, normal, offset, scratch):  # pragma: no cover - numba
    """Sutherland–Hodgman, polygon by polygon, half-plane by half-plane, in place (see :func:`clip_each`)."""
    for m in range(xy.shape[0]):
        n = count[m]
        for e in range(indptr[m], indptr[m + 1]):
            if n == 0:
                break
            n = clip_one(xy[m], n, normal[e, 0], normal[e, 1], offset[e], scratch)
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


@numba.njit(cache=True)
def _disk_overlap(xy, count, centres, disk, out, scratch, clipped):  # pragma: no cover - numba
    """Area of polygon ``m`` within the convex polygon ``disk`` moved to ``centres[m]`` (see :func:`disk_overlap`)."""
    sides = disk.shape[0]
    for m in range(xy.shape[0]):
        n = count[m]
        for v in range(n):
            clipped[v, 0] = xy[m, v, 0]
            clipped[v, 1] = xy[m, v, 1]
        for e in range(sides):
            if n == 0:
                break
            f = e + 1 if e + 1 < sides else 0
            ex, ey = disk[e, 0] + centres[m, 0], disk[e, 1] + centres[m, 1]
            nx, ny = disk[f, 1] - disk[e, 1], disk[e, 0] - disk[f, 0]  # the outward normal of a counter-clockwise side
            n = clip_one(clipped, n, nx, ny, ex * nx + ey * ny, scratch)
        area = 0.0
        if n >= 3:
            for v in range(n):
                w = v + 1 if v + 1 < n else 0
                area += clipped[v, 0] * clipped[w, 1] - clipped[w, 0] * clipped[v, 1]
        out[m] = 0.5 * area


def disk_overlap(poly: Polygons, centres: np.ndarray, radius: float, vertices: int) -> np.ndarray:
    """Area ``(M,)`` of each polygon within the regular ``vertices``-gon of ``radius`` about ``centres`` ``(M, 2)``.

    The polygon clipped by the sides of the other (both convex), compiled; the same area as shapely's
    ``area(intersection(...))`` of the two to rounding (a few ulps of the area).
    """
    disk = regular(1, radius, vertices, vertices).xy[0]
    m, width = poly.xy.shape[0], poly.xy.shape[1] + vertices + 1
    out = np.zeros(m)
    _disk_overlap(poly.xy, poly.count.astype(np.int64), np.ascontiguousarray(centres, dtype=np.float64), disk, out,
                  np.empty((width, 2)), np.empty((width, 2)))
    return out


@numba.njit(cache=True)
def _numpy_sum(a, n, stack):  # pragma: no cover - numba
    """``a[:n]`` added up in NumPy's order (its pairwise summation, ``loops_utils.h``): bit for bit ``a[:n].sum()``.

    A run of up to 128 is added with eight running sums (then the rest, one by one; under 8, one by one); a longer
    one is halved at a multiple of 8 and its halves' sums added. The halving is walked with ``stack`` ``(4, 64)``
    (lo, n, stage, left half's sum) rather than by recursion (a cached numba function must not call itself).
    """
    top = 0
    stack[0, 0], stack[1, 0] = 0.0, n
    while True:
        lo, k = int(stack[0, top]), int(stack[1, top])
        if k > 128:  # halve: the left half first
            half = k // 2
            half -= half % 8
            stack[2, top] = 1.0
            stack[0, top + 1], stack[1, top + 1], stack[2, top + 1] = lo, half, 0.0
            top += 1
            continue
        if k < 8:
            v = -0.0
            for i in range(k):
                v += a[lo + i]
        else:
            r0, r1, r2, r3 = a[lo], a[lo + 1], a[lo + 2], a[lo + 3]
            r4, r5, r6, r7 = a[lo + 4], a[lo + 5], a[lo + 6], a[lo + 7]
            i = 8
            while i < k - (k % 8):
                b = lo + i
                r0, r1, r2, r3 = r0 + a[b], r1 + a[b + 1], r2 + a[b + 2], r3 + a[b + 3]
                r4, r5, r6, r7 = r4 + a[b + 4], r5 + a[b + 5], r6 + a[b + 6], r7 + a[b + 7]
                i += 8
            v = ((r0 + r1) + (r2 + r3)) + ((r4 + r5) + (r6 + r7))
            while i < k:
                v += a[lo + i]
                i += 1
        top -= 1
        while top >= 0 and stack[2, top] == 2.0:  # a right half's sum: add it to its left half's
            v = stack[3, top] + v
            top -= 1
        if top < 0:
            return v
        stack[3, top], stack[2, top] = v, 2.0  # a left half's sum: now the right half
        lo, k = int(stack[0, top]), int(stack[1, top])
        half = k // 2
        half -= half % 8
        stack[0, top + 1], stack[1, top + 1], stack[2, top + 1] = lo + half, k - half, 0.0
        top += 1


@numba.njit(cache=True)
def _area_centroid(xy, count, area, centroid):  # pragma: no cover - numba
    """See :func:`area_centroid`: the shoelace sums in NumPy's order over the padded width, as its array form had."""
    width = xy.shape[1]
    cross = np.zeros(width)
    stack = np.zeros((4, 64))
    for m in range(xy.shape[0]):
        n = count[m]
        mx, my, sx, sy = 0.0, 0.0, 0.0, 0.0
        for v in range(width):
            if v >= n:
                cross[v] = 0.0
                continue
            u = v + 1 if v + 1 < n else 0
            c = xy[m, v, 0] * xy[m, u, 1] - xy[m, u, 0] * xy[m, v, 1]
            cross[v] = c
            mx += (xy[m, v, 0] + xy[m, u, 0]) * c
            my += (xy[m, v, 1] + xy[m, u, 1]) * c
            sx += xy[m, v, 0]
            sy += xy[m, v, 1]
        a = 0.5 * (0.0 + _numpy_sum(cross, width, stack))
        area[m] = a
        if abs(a) <= 1e-15:
            k = max(n, 1)
            centroid[m, 0] = sx / k
            centroid[m, 1] = sy / k
        else:
            centroid[m, 0] = mx / (6.0 * a)
            centroid[m, 1] = my / (6.0 * a)


def area_centroid(poly: Polygons) -> tuple[np.ndarray, np.ndarray]:
    """Area ``(M,)`` and centroid ``(M, 2)`` of every polygon (a polygon of no area: its vertices' mean, or 0).

    Compiled; the sums run in the order NumPy's ``sum`` over the padded ``(M, W)`` arrays ran them (pairwise over
    the width for the area, vertex by vertex for the moments), so the results are those of the array form bit for
    bit (``tests/test_voronoi_baselines.py`` checks it against that form).
    """
    m = len(poly.count)
    area, centroid = np.zeros(m), np.zeros((m, 2))
    _area_centroid(np.ascontiguousarray(poly.xy, dtype=np.float64), poly.count.astype(np.int64), area, centroid)
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
