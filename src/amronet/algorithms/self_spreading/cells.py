"""The map's cells as self-spreading's compiled step reads them first: one byte a cell, two flags.

Each step every moving router reads the map where it stands, twice: its range ring asks whether any beam can meet the
grid from its cell (the cell's byte of ``blocked``, its 8-byte ``clear`` and its byte of
:func:`~amronet.engine.sensing.quiet_cells`), and its move asks whether the cell's clearance leaves room for the whole
step (:func:`~amronet.engine.motion.plan_one`). Routers stand all over the map, so each of those reads is a cache line
of its own (at N = 3 000 on the scaled ``hospital_section`` the three arrays hold 4.8 MB, more than the processor's
second-level cache); nearly always (97 % of the routers there) the answers are "no beam meets the grid" and "room
enough". :func:`cell_flags` keeps both answers in one byte per cell (0.5 MB for that map), so that the common case
reads one line; where a flag is not set the kernels ask the arrays themselves, as before. The flags are the same
comparisons on the same numbers, so every ring and move is the same bit for bit:

* :data:`QUIET_RING` is the ring's own test (:func:`~amronet.engine.sensing.cast_ring_one`): the cell is free and
  its clearance less one cell reaches beyond the beams, or no beam cast from it can meet the grid.
* :data:`ROOMY` is the move's test ``clear >= radius + length + 1.5 res`` for the largest body and longest step it
  was computed for (:class:`Roomy`): floating-point sums and products round monotonically, so a smaller body or a
  shorter step passes it too; :func:`drive_roomy` takes the flag only for those and otherwise asks the clearance.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numba import njit

from amronet.engine.kernel_data import Grid
from amronet.engine.motion import commit_one, plan_one
from amronet.engine.sensing import quiet_cells
from amronet.world.occupancy import OccupancyMap

__all__ = ["QUIET_RING", "ROOMY", "Roomy", "cell_flags", "drive_roomy"]

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
        ring = (blocked == 0) & ((clear - res >= float(sensor_range)) | (quiet != 0))  # cast_ring_one's test
        room = clear >= (float(roomy.radius) + float(roomy.length)) + 1.5 * res  # plan_one's, in its order
        flags = ring.astype(np.uint8) * np.uint8(QUIET_RING) | room.astype(np.uint8) * np.uint8(ROOMY)
        flags.flags.writeable = False
        omap._cache[key] = flags
    return omap._cache[key]


@njit(cache=True, inline="always")
def drive_roomy(grid, flags, roomy, i, heading, length, xy, radius, bodies, csr, near):  # pragma: no cover - numba
    """:func:`~amronet.engine.motion.drive_one`, bit for bit, asking the cell's :data:`ROOMY` flag first.

    Where the flag holds for robot ``i``'s cell and its body and step are no larger than ``roomy``'s, the path is
    clear of the map (the test :func:`~amronet.engine.motion.plan_one` would make passes); otherwise
    :func:`~amronet.engine.motion.plan_one` asks the clearance itself.
    """
    blocked, clear, ox, oy, res = grid
    x0 = xy[i, 0]
    y0 = xy[i, 1]
    c0 = int(math.floor((x0 - ox) / res))
    r0 = int(math.floor((y0 - oy) / res))
    rows, cols = flags.shape
    if (0 <= r0 < rows and 0 <= c0 < cols and (flags[r0, c0] & ROOMY) != 0 and length <= roomy.length
            and radius[i] <= roomy.radius):
        free = True
        nx = x0 + length * math.cos(heading)  # plan_one's end point
        ny = y0 + length * math.sin(heading)
    else:
        free, nx, ny = plan_one(blocked, clear, ox, oy, res, x0, y0, heading, length, radius[i])
    if not free:  # drive_one's own steps from here (one copy of each when inlined)
        return True, 0.0
    return commit_one(i, x0, y0, nx, ny, xy, radius, bodies, csr[0], csr[1], csr[2], near)
