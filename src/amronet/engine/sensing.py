"""Range sensors: rings of beams ray-cast against the occupancy grid and against other robots.

A sensor ring of ``n`` beams is spread evenly around the body, beam 0 pointing along the robot's heading.
Each beam returns the distance to the first obstacle cell or robot body it meets, or its maximum range.
Grid rays march cell by cell, skipping ahead where the clearance map proves the way is free; robot bodies are
discs, tested exactly.
"""

from __future__ import annotations

import functools
import math
from typing import NamedTuple

import numpy as np
from numba import njit
from scipy import ndimage

from amronet.engine.neighbours import neighbour_csr
from amronet.engine.radio import NeighbourTable
from amronet.world.occupancy import OccupancyMap
from amronet.world.space import clearance

__all__ = ["QuietRing", "beam_angles", "body_table", "cast_bodies_one", "cast_grid_one", "cast_rings", "quiet_cells",
           "range_scan"]

QUIET_MARGIN = 0.01
"""Cells of slack (on top of the sensor's range) in :func:`quiet_cells`: far more than any rounding of a beam's
points or cells."""


class QuietRing(NamedTuple):
    """A sensor ring as :func:`cast_rings` reads it: the beams and where they cannot meet the grid."""

    angles: np.ndarray
    """``(n_beams,)``: the beams' angles from the heading (:func:`beam_angles`)."""
    sensor_range: float
    """A beam's reach, metres."""
    quiet: np.ndarray
    """``uint8 (H, W)``: bit 0 set on the map's cells from which no beam meets the grid (:func:`quiet_cells`, or
    a caller's flags whose bit 0 means that and whose other bits are the caller's)."""


@functools.cache
def beam_angles(n_beams: int) -> np.ndarray:
    """Angles of ``n_beams`` evenly spaced beams relative to the heading, beam 0 straight ahead (read-only)."""
    angles = np.arange(n_beams) * (2.0 * np.pi / n_beams)
    angles.setflags(write=False)
    return angles


@njit(cache=True, inline="always")
def cast_grid_one(blocked, clear, ox, oy, res, x, y, heading, angles, max_range, out):  # pragma: no cover - numba
    """The beams of one robot at ``(x, y)`` with ``heading`` against the grid, into ``out`` ``(n_beams,)``."""
    rows, cols = blocked.shape
    c0 = int(math.floor((x - ox) / res))
    r0 = int(math.floor((y - oy) / res))
    if 0 <= r0 < rows and 0 <= c0 < cols and not blocked[r0, c0] and clear[r0, c0] - res >= max_range:
        for k in range(angles.shape[0]):
            out[k] = max_range  # nothing within reach in any direction
        return
    for k in range(angles.shape[0]):
        a = heading + angles[k]
        dx = math.cos(a)
        dy = math.sin(a)
        t = 0.0
        hit = max_range
        while t < max_range:
            px = x + dx * t
            py = y + dy * t
            c = int(math.floor((px - ox) / res))
            r = int(math.floor((py - oy) / res))
            if r < 0 or r >= rows or c < 0 or c >= cols or blocked[r, c]:
                hit = t
                break
            step = clear[r, c] - res
            if step < 0.5 * res:
                step = 0.5 * res
            t += step
        out[k] = min(hit, max_range)


@njit(cache=True)
def _cast_grid(blocked, clear, ox, oy, res, who, xy, heading, angles, max_range, out):  # pragma: no cover - numba
    for s in range(who.shape[0]):
        i = who[s]
        cast_grid_one(blocked, clear, ox, oy, res, xy[i, 0], xy[i, 1], heading[i], angles, max_range, out[s])


@njit(cache=True, inline="always")
def cast_bodies_one(i, indptr, indices, dist, xy, heading, angles, max_range, other_radius, big,
                    out):  # pragma: no cover - numba
    """Shorten robot ``i``'s beams ``out`` ``(n_beams,)`` that meet another robot's disc (exact ray-disc test).

    ``big``: the largest body radius (neighbours farther than ``max_range + big`` cannot be met).
    """
    for e in range(indptr[i], indptr[i + 1]):
        if dist[e] > max_range + big:
            continue
        j = indices[e]
        vx = xy[j, 0] - xy[i, 0]
        vy = xy[j, 1] - xy[i, 1]
        rj = other_radius[j]
        dist2 = vx * vx + vy * vy
        if dist2 > (max_range + rj) ** 2:
            continue
        for k in range(angles.shape[0]):
            a = heading + angles[k]
            tca = vx * math.cos(a) + vy * math.sin(a)
            if tca <= 0.0:
                continue
            d2 = dist2 - tca * tca
            if d2 > rj * rj:
                continue
            t = max(tca - math.sqrt(rj * rj - d2), 0.0)
            if t < out[k]:
                out[k] = t


def quiet_cells(omap: OccupancyMap, max_range: float) -> np.ndarray:
    """``uint8 (H, W)``: 1 where no beam of reach ``max_range`` cast from any point of the cell can meet the grid.

    Every cell that comes within ``max_range`` (and :data:`QUIET_MARGIN` cells) of the cell's square is free and on
    the map: every point a beam of :func:`cast_grid_one` tests is then in a free cell, and each beam reads
    ``max_range``. Computed once per map and range, cached in ``omap._cache``, read-only.
    """
    key = ("quiet_cells", float(max_range))
    if key not in omap._cache:
        res = omap.resolution
        k = int(math.ceil(max_range / res + QUIET_MARGIN)) + 1
        dr, dc = np.mgrid[-k:k + 1, -k:k + 1]
        gap = np.hypot(np.maximum(np.abs(dr) - 1, 0), np.maximum(np.abs(dc) - 1, 0))  # square to square, cells
        near = gap <= max_range / res + QUIET_MARGIN
        padded = np.pad(omap.blocked, k, constant_values=True)
        quiet = ~ndimage.binary_dilation(padded, structure=near)[k:-k, k:-k]
        quiet = quiet.astype(np.uint8)
        quiet.flags.writeable = False
        omap._cache[key] = quiet
    return omap._cache[key]


@njit(cache=True, inline="always")
def cast_rings(grid, ring, who, xy, heading, radius, big, bodies, csr, dirs, out,
               close):  # pragma: no cover - numba
    """The rings of the robots ``who`` into ``out`` ``(len(who), n_beams)``: the grid's beams, then the bodies'.

    Bit for bit :func:`cast_grid_one`, then (``bodies``) :func:`cast_bodies_one`. ``grid``: the map's
    :class:`~amronet.engine.kernel_data.Grid`; ``ring``: a :class:`QuietRing`; ``radius`` and ``big``: every
    robot's body radius and the largest; ``csr``: ``(indptr, indices, dist)``, the bodies near each
    robot; ``dirs``: scratch ``(cos, sin)``, ``(n_beams,)`` each. ``close``: ``(reach, first, edges, cells)``,
    what a later pass over the same robots (their moves) reads: ``cells`` ``uint8 (len(who),)`` gets each robot's
    byte of ``ring.quiet`` where it stands (0 off the grid); with
    ``bodies``, robot ``who[m]``'s links no longer than ``reach`` (at least ``ring.sensor_range + big``) are listed,
    in row order, as the positions ``edges[first[m]:first[m + 1]]`` in ``csr`` (``first``: ``(len(who) + 1,)``;
    ``edges``: as long as ``csr``'s links, and one more), and the bodies are cast from that list: a later pass over
    the same robots' near links (their moves) reads a link or two each instead of a dozen. Where a robot's cell is
    quiet the grid's beams read the range without a march, and each beam's direction is computed once, for the grid
    and the bodies, and only when one of them needs it: the same numbers, fewer sines. Elsewhere the beams march
    side by side, a step of each beam still marching in turn (each beam's steps are those of
    :func:`cast_grid_one`, and the processor overlaps the beams' chains of dependent loads). The loop over the robots is
    written here, not around a per-robot function: numba counts the references of every array handed to a function,
    even an inlined one, at each call, and at N = 3 000 those atomic counts took longer than the rings themselves.
    """
    angles, max_range, quiet = ring
    indptr, indices, dist = csr
    cos_a, sin_a = dirs
    reach, first, edges, cells = close
    reach = max(reach, max_range + big)
    listed = 0
    first[0] = 0
    blocked, clear, ox, oy, res = grid
    rows, cols = blocked.shape
    n_beams = angles.shape[0]
    travel = np.empty(n_beams)  # the march: how far each beam has come, and the beams still marching
    marching = np.empty(n_beams, np.int64)
    for m in range(who.shape[0]):
        i = who[m]
        x = xy[i, 0]
        y = xy[i, 1]
        h = heading[i]
        c0 = int(math.floor((x - ox) / res))
        r0 = int(math.floor((y - oy) / res))
        have = False
        inside = 0 <= r0 < rows and 0 <= c0 < cols
        flags = quiet[r0, c0] if inside else 0
        cells[m] = flags
        # the quiet bit first: one byte, where blocked and clear take a cache line each (a quiet cell is free)
        if inside and ((flags & 1) != 0 or (not blocked[r0, c0] and clear[r0, c0] - res >= max_range)):
            for k in range(n_beams):
                out[m, k] = max_range
        else:
            have = True
            for k in range(n_beams):
                a = h + angles[k]
                cos_a[k] = math.cos(a)
                sin_a[k] = math.sin(a)
                out[m, k] = max_range
                travel[k] = 0.0
                marching[k] = k
            live = n_beams if 0.0 < max_range else 0
            while live > 0:  # cast_grid_one's march, the beams side by side
                kept = 0
                for q in range(live):
                    k = marching[q]
                    t = travel[k]
                    px = x + cos_a[k] * t
                    py = y + sin_a[k] * t
                    c = int(math.floor((px - ox) / res))
                    r = int(math.floor((py - oy) / res))
                    if r < 0 or r >= rows or c < 0 or c >= cols or blocked[r, c]:
                        out[m, k] = min(t, max_range)
                        continue
                    step = clear[r, c] - res
                    if step < 0.5 * res:
                        step = 0.5 * res
                    t += step
                    if t < max_range:
                        travel[k] = t
                        marching[kept] = k
                        kept += 1
                live = kept
        if not bodies:
            continue
        start = listed
        for e in range(indptr[i], indptr[i + 1]):  # the row's near links, without a branch
            edges[listed] = e
            listed += dist[e] <= reach
        first[m + 1] = listed
        for q in range(start, listed):  # cast_bodies_one
            e = edges[q]
            if dist[e] > max_range + big:
                continue
            j = indices[e]
            vx = xy[j, 0] - x
            vy = xy[j, 1] - y
            rj = radius[j]
            dist2 = vx * vx + vy * vy
            if dist2 > (max_range + rj) ** 2:
                continue
            for k in range(n_beams):
                if not have:
                    a = h + angles[k]
                    cos_a[k] = math.cos(a)
                    sin_a[k] = math.sin(a)
                tca = vx * cos_a[k] + vy * sin_a[k]
                if tca <= 0.0:
                    continue
                d2 = dist2 - tca * tca
                if d2 > rj * rj:
                    continue
                t = max(tca - math.sqrt(rj * rj - d2), 0.0)
                if t < out[m, k]:
                    out[m, k] = t
            have = True


@njit(cache=True)
def _cast_bodies(who, indptr, indices, dist, xy, heading, angles, max_range, other_radius, out):  # pragma: no cover
    """Shorten beams that meet another robot's disc (exact ray-disc intersection)."""
    big = other_radius.max()
    for s in range(who.shape[0]):
        i = who[s]
        cast_bodies_one(i, indptr, indices, dist, xy, heading[i], angles, max_range, other_radius, big, out[s])


def body_table(xy: np.ndarray, reach: float, table: NeighbourTable | None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """CSR ``(indptr, indices, dist)`` holding every pair of robots within ``reach`` of each other.

    The table's geometric view when it reaches that far (every body within its ``r``, whatever the walls do to the
    radio links), otherwise a neighbour search of its own (of the table's groups; one group without a table).
    """
    near = None if table is None else table.geometric
    if near is not None and reach <= near.r:
        return near.indptr, near.indices, near.dist
    return neighbour_csr(xy, reach, None if table is None else table.groups)


def range_scan(
    omap: OccupancyMap,
    xy: np.ndarray,
    heading: np.ndarray,
    who: np.ndarray,
    n_beams: int,
    max_range: float,
    *,
    radius: np.ndarray | None = None,
    table: NeighbourTable | None = None,
) -> np.ndarray:
    """Read the sensor rings of some robots.

    Args:
        omap: The map; occupied and unknown cells and everything outside the map stop a beam.
        xy: Positions of **all** robots, ``(N, 2)``.
        heading: Headings of all robots, ``(N,)``.
        who: Indices of the robots whose sensors are read, ``(M,)``.
        n_beams: Beams per ring.
        max_range: Maximum range of a beam in metres.
        radius: Body radius of all robots, ``(N,)``; when given (with ``table``) other robots stop beams too.
        table: The radio medium's neighbour table for ``xy``: bodies within its range are found from it; a
            sensor reaching farther gets a neighbour search of its own (of the table's groups).

    Returns:
        Distances ``(M, n_beams)`` in metres, each in ``[0, max_range]``; row ``m`` belongs to robot ``who[m]``.
    """
    who = np.asarray(who, dtype=np.int64)
    out = np.empty((len(who), n_beams))
    if len(who) == 0:
        return out
    angles = beam_angles(n_beams)
    blocked = omap.blocked.view(np.uint8)
    _cast_grid(
        blocked, clearance(omap), float(omap.origin[0]), float(omap.origin[1]), float(omap.resolution),
        who, xy, heading, angles, float(max_range), out,
    )
    if radius is not None and table is not None and len(xy) > 1:
        indptr, indices, dist = body_table(xy, float(max_range + radius.max()), table)
        _cast_bodies(who, indptr, indices, dist, xy, heading, angles, float(max_range), radius, out)
    return out
