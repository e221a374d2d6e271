"""The map's cells as self-spreading's compiled step reads them first: one byte a cell, two flags.

Each step every moving router reads the map where it stands, twice: its range ring asks whether any beam can meet the
grid from its cell (the cell's byte of ``blocked``, its 8-byte ``clear`` and its byte of
:func:`~amronet.engine.sensing.quiet_cells`), and its move asks whether the cell's clearance leaves room for the whole
step (:func:`~amronet.engine.motion.plan_one`). Routers stand all over the map, so each of those reads is a cache line
of its own (at N = 3 000 on the scaled ``hospital_section`` the three arrays hold 4.8 MB, more than the processor's
second-level cache); nearly always (97 % of the routers there) the answers are "no beam meets the grid" and "room
enough". :func:`cell_flags` keeps both answers in one byte per cell (0.5 MB for that map), so that the common case
reads one line, once: the ring hands the byte it read to the move (:func:`drive_rooms`); where a flag is not set the
kernels ask the arrays themselves, as before. The flags are the same comparisons on the same numbers, so every ring
and move is the same bit for bit:

* :data:`QUIET_RING` is the ring's own test (:func:`~amronet.engine.sensing.cast_rings`): the cell is free and
  its clearance less one cell reaches beyond the beams, or no beam cast from it can meet the grid.
* :data:`ROOMY` is the move's test ``clear >= radius + length + 1.5 res`` for the largest body and longest step it
  was computed for (:class:`Roomy`): floating-point sums and products round monotonically, so a smaller body or a
  shorter step passes it too; :func:`drive_rooms` takes the flag only for those and otherwise asks the clearance.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numba import njit

from amronet.engine.kernel_data import Grid
from amronet.engine.motion import plan_one
from amronet.engine.sensing import quiet_cells
from amronet.world.occupancy import OccupancyMap

__all__ = ["QUIET_RING", "ROOMY", "Roomy", "cell_flags", "drive_rooms", "same_rows"]

QUIET_RING = 1
"""Flag: no beam of the ring cast from anywhere in the cell meets the grid (all read the range)."""
ROOMY = 2
"""Flag: the cell's clearance leaves room for a step of :attr:`Roomy.length` of a body of :attr:`Roomy.radius`."""


class Roomy(NamedTuple):
    """What the :data:`ROOMY` flag was computed for."""

    length: float
    """The longest step, metres."""
    radius: float
    """The largest body's radius, metres."""


def cell_flags(omap: OccupancyMap, grid: Grid, sensor_range: float, roomy: Roomy) -> np.ndarray:
    """``uint8 (H, W)``: each cell's :data:`QUIET_RING` and :data:`ROOMY` flags (cached in ``omap._cache``, read-only).

    Args:
        omap: The map (its :func:`~amronet.engine.sensing.quiet_cells` and its cache).
        grid: The map's grid, as the kernels read it.
        sensor_range: The ring's reach, metres.
        roomy: The step and body the :data:`ROOMY` flag is for.
    """
    key = ("self_spreading.cell_flags", float(sensor_range), float(roomy.length), float(roomy.radius))
    if key not in omap._cache:
        blocked, clear, res = grid.blocked, grid.clear, float(grid.res)
        quiet = quiet_cells(omap, sensor_range)
        ring = (blocked == 0) & ((clear - res >= float(sensor_range)) | (quiet != 0))  # cast_rings' test
        room = clear >= (float(roomy.radius) + float(roomy.length)) + 1.5 * res  # plan_one's, in its order
        flags = ring.astype(np.uint8) * np.uint8(QUIET_RING) | room.astype(np.uint8) * np.uint8(ROOMY)
        flags.flags.writeable = False
        omap._cache[key] = flags
    return omap._cache[key]


@njit(cache=True, inline="always")
def drive_rooms(grid, cells, roomy, movers, heading, length, xy, radius, bodies, csr, done,
                near):  # pragma: no cover - numba
    """:func:`~amronet.engine.motion.drive_one` for each of ``movers`` in turn, asking the :data:`ROOMY` flag first.

    Bit for bit. Mover ``m`` (robot ``i = movers[m]``) goes ``length[m]`` along ``heading[i]``; with ``done``
    ``(refused, distance)``, ``refused[i]`` says whether it was refused and ``distance[i]`` grows by how far it
    went. ``cells[m]``: the flags of the cell it stands in before its move (0 off the map), as
    :func:`~amronet.engine.sensing.cast_rings` read them for its ring (nobody moves a mover but its own move). Where
    the flag holds for its cell and its body and step are no larger than ``roomy``'s, the path is clear
    of the map (the test :func:`~amronet.engine.motion.plan_one` would make passes); otherwise
    :func:`~amronet.engine.motion.plan_one` asks the clearance itself. The bodies' half is
    :func:`~amronet.engine.motion.commit_one`'s, written out in the loop: numba counts the references of every array
    handed to a function, inlined or not, at each call, and at N = 3 000 that took a third of the moves' time.
    ``near``: ``(near, listed, reach, first, edges)``: a body farther than ``near`` before the moves cannot touch the
    mover after its step; with ``listed`` (``csr`` is the table the movers' rings were cast from) ``first, edges``
    is the list of their links no longer than ``reach`` that :func:`~amronet.engine.sensing.cast_rings` made, and
    where ``near <= reach`` the bodies are read from it (every link it leaves out is farther than ``near``, which the
    test skips: the same moves), otherwise from the rows.
    """
    blocked, clear, ox, oy, res = grid
    indptr, indices, dist = csr
    refused, distance = done
    near, listed, reach, first, edges = near
    listed = listed and near <= reach
    for m in range(movers.shape[0]):
        i = movers[m]
        step = length[m]
        x0 = xy[i, 0]
        y0 = xy[i, 1]
        if (cells[m] & ROOMY) != 0 and step <= roomy.length and radius[i] <= roomy.radius:
            free = True
            nx = x0 + step * math.cos(heading[i])  # plan_one's end point
            ny = y0 + step * math.sin(heading[i])
        else:
            free, nx, ny = plan_one(blocked, clear, ox, oy, res, x0, y0, heading[i], step, radius[i])
        refuse = not free
        if free and bodies:  # commit_one
            lo, hi = (first[m], first[m + 1]) if listed else (indptr[i], indptr[i + 1])
            for q in range(lo, hi):
                e = edges[q] if listed else q
                if dist[e] > near:
                    continue  # too far apart before this step to touch after it
                j = indices[e]
                reach = radius[i] + radius[j]
                ex = nx - xy[j, 0]
                ey = ny - xy[j, 1]
                new2 = ex * ex + ey * ey
                if new2 >= reach * reach:
                    continue
                ox_ = x0 - xy[j, 0]
                oy_ = y0 - xy[j, 1]
                if new2 < ox_ * ox_ + oy_ * oy_ - 1e-18:
                    refuse = True
                    break
        travelled = 0.0
        if not refuse:
            xy[i, 0] = nx
            xy[i, 1] = ny
            travelled = math.hypot(nx - x0, ny - y0)
        refused[i] = refuse
        distance[i] += travelled


@njit(cache=True, inline="always")
def same_rows(s_indptr, s_indices, s_dist, d_indptr, d_indices, d_dist):  # pragma: no cover - numba
    """Whether the rings' and the moves' neighbour lists are the same arrays: a stretch's table, and most steps'.

    Then the moves may read the rings' list of near links (:func:`drive_rooms`).
    """
    return (s_indptr.ctypes.data == d_indptr.ctypes.data and s_indices.ctypes.data == d_indices.ctypes.data
            and s_dist.ctypes.data == d_dist.ctypes.data and s_indptr.shape[0] == d_indptr.shape[0]
            and s_indices.shape[0] == d_indices.shape[0] and s_dist.shape[0] == d_dist.shape[0])
