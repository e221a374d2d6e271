"""What each robot remembers of the obstacles its own range sensors hit: the free space it has seen, not the map.

Every beam of a robot's ring that stops short of its range puts an obstacle point at ``p + d (cos a, sin a)``
(``a`` the beam's direction). A beam stopped by another robot's body is not an obstacle: a point within that
neighbour's body radius (plus :data:`BODY_MARGIN_M`) of where a heard neighbour announces it is, is dropped. The
rest are remembered per robot, once per grid cell of ``cell_m`` metres, in a ring of the ``capacity`` most recent
points. The Voronoi baselines cut a robot's cell with the line through each remembered point that faces the robot
(:func:`amronet.algorithms.common.cells.local_cells`): what lies beyond a wall it has seen is not its free space.
"""

from __future__ import annotations

import numba
import numpy as np

from amronet.engine.kernel_data import Csr
from amronet.engine.sensing import beam_angles
from amronet.engine.table import NeighbourTable

__all__ = ["BODY_MARGIN_M", "ObstacleMemory"]

BODY_MARGIN_M = 0.02
"""A hit this close to a heard neighbour's body (beyond its radius) is that body (our choice: two sensor cells)."""


class ObstacleMemory:
    """The obstacle points robots remember, a ring of ``capacity`` points per robot.

    Args:
        n: Robots.
        capacity: Points per robot (0: remember nothing).
        cell_m: Points in one grid cell of this size are one point.
    """

    def __init__(self, n: int, capacity: int, cell_m: float) -> None:
        self.points = np.zeros((n, capacity, 2))
        self.keys = np.full((n, capacity), -1, dtype=np.int64)
        self.stored = np.zeros(n, dtype=np.int64)
        """Points ever stored per robot (the ring's next slot is ``stored % capacity``)."""
        self.cell_m = cell_m

    def remember(self, robots: np.ndarray, scans: np.ndarray, xy: np.ndarray, heading: np.ndarray,
                 sensor_range: float, table: NeighbourTable, radius: np.ndarray) -> None:
        """Remember the obstacle points of ``scans`` ``(M, B)``, the readings of ``robots`` ``(M,)``.

        Args:
            robots: The robots read.
            scans: Their range readings.
            xy: Positions of all nodes (what they announce; the robots' own).
            heading: Headings of all nodes.
            sensor_range: The beams' range.
            table: This step's neighbour table (who each robot hears).
            radius: Body radius of every node (what neighbours announce of themselves).
        """
        capacity = self.keys.shape[1]
        if capacity == 0 or len(robots) == 0:
            return
        row, beam = np.nonzero(scans < sensor_range - 1e-9)
        # nonzero's rows are a strided view, but contiguous for one hit: one layout, so the kernel compiles once
        row = np.ascontiguousarray(row)
        angle = heading[robots[row]] + beam_angles(scans.shape[1])[beam]
        geometric = table.geometric
        _remember(robots, row, scans[row, beam], np.cos(angle), np.sin(angle), xy, radius,
                  Csr(geometric.indptr, geometric.indices, geometric.dist), self.cell_m, self.points, self.keys,
                  self.stored)

    def remembered(self) -> tuple[np.ndarray, np.ndarray]:
        """``(points (N, C, 2), filled (N,))``: every robot's remembered points, the first ``filled`` of its row."""
        return self.points, np.minimum(self.stored, self.keys.shape[1])


@numba.njit(cache=True)
def _remember(robots, row, reach, cos, sin, xy, radius, heard, cell_m, points, keys, stored):  # pragma: no cover
    """Store the hits ``(row, reach, cos, sin)`` (by rank in ``robots``, in beam order) in their robots' rings.

    Per robot, in beam order: a hit on the body of a node it hears (``heard``, the table's geometric rows;
    :data:`BODY_MARGIN_M`) is dropped, then a hit in a grid cell that an earlier hit of this step or a remembered
    point (before this step) has; the rest go to the ring's next slots (bit for bit what the array form did: the
    cosines and sines come from NumPy).
    """
    indptr, indices = heard.indptr, heard.indices
    capacity = keys.shape[1]
    fresh = np.empty(row.shape[0], dtype=np.int64)  # this step's new keys of the robot at hand
    fresh_xy = np.empty((row.shape[0], 2))
    h = 0
    while h < row.shape[0]:
        i = robots[row[h]]
        k = 0
        while h < row.shape[0] and robots[row[h]] == i:
            x = xy[i, 0] + reach[h] * cos[h]
            y = xy[i, 1] + reach[h] * sin[h]
            h += 1
            body = False
            for e in range(indptr[i], indptr[i + 1]):
                j = indices[e]
                if np.hypot(x - xy[j, 0], y - xy[j, 1]) - radius[j] <= BODY_MARGIN_M:
                    body = True
                    break
            if body:
                continue
            key = ((np.int64(np.floor(x / cell_m)) + (1 << 31)) * (1 << 32)
                   + (np.int64(np.floor(y / cell_m)) + (1 << 31)))
            seen = False
            for f in range(k):
                seen = seen or fresh[f] == key
            for f in range(capacity):
                seen = seen or keys[i, f] == key
            if not seen:
                fresh[k] = key
                fresh_xy[k, 0] = x
                fresh_xy[k, 1] = y
                k += 1
        for f in range(k):
            slot = (stored[i] + f) % capacity
            points[i, slot, 0] = fresh_xy[f, 0]
            points[i, slot, 1] = fresh_xy[f, 1]
            keys[i, slot] = fresh[f]
        stored[i] += k
