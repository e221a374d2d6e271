"""What each robot remembers of the obstacles its own range sensors hit: the free space it has seen, not the map.

Every beam of a robot's ring that stops short of its range puts an obstacle point at ``p + d (cos a, sin a)``
(``a`` the beam's direction). A beam stopped by another robot's body is not an obstacle: a point within that
neighbour's body radius (plus :data:`BODY_MARGIN_M`) of where a heard neighbour announces it is, is dropped. The
rest are remembered per robot, once per grid cell of ``cell_m`` metres, in a ring of the ``capacity`` most recent
points. The Voronoi baselines cut a robot's cell with the line through each remembered point that faces the robot
(:func:`amronet.algorithms.common.cells.local_cells`): what lies beyond a wall it has seen is not its free space.
"""

from __future__ import annotations

import numpy as np

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
        b = scans.shape[1]
        hit = scans < sensor_range - 1e-9
        row, beam = np.nonzero(hit)
        if len(row) == 0:
            return
        who = robots[row]
        angle = heading[who] + beam_angles(b)[beam]
        point = xy[who] + scans[row, beam, None] * np.stack([np.cos(angle), np.sin(angle)], axis=1)
        keep = ~_on_a_body(who, point, xy, table, radius)
        who, point = who[keep], point[keep]
        cell = np.floor(point / self.cell_m).astype(np.int64)
        key = (cell[:, 0] + (1 << 31)) * (1 << 32) + (cell[:, 1] + (1 << 31))
        key_who = np.stack([who, key], axis=1)
        _, first = np.unique(key_who, axis=0, return_index=True)  # once per robot and cell in this step
        first = np.sort(first)
        who, point, key = who[first], point[first], key[first]
        known = (self.keys[who] == key[:, None]).any(axis=1)
        who, point, key = who[~known], point[~known], key[~known]
        if len(who) == 0:
            return
        order = np.argsort(who, kind="stable")
        who, point, key = who[order], point[order], key[order]
        starts = np.searchsorted(who, who, side="left")
        rank = np.arange(len(who)) - starts
        slot = (self.stored[who] + rank) % capacity
        self.points[who, slot] = point
        self.keys[who, slot] = key
        np.add.at(self.stored, who, 1)

    def near(self, robots: np.ndarray, xy: np.ndarray, reach: float) -> tuple[np.ndarray, np.ndarray]:
        """The remembered points within ``reach`` of each robot: ``(rank in robots (K,), offset from it (K, 2))``."""
        capacity = self.keys.shape[1]
        if capacity == 0 or len(robots) == 0:
            return np.zeros(0, dtype=np.int64), np.zeros((0, 2))
        filled = np.arange(capacity)[None, :] < np.minimum(self.stored[robots], capacity)[:, None]
        offset = self.points[robots] - xy[robots][:, None, :]
        close = filled & (np.hypot(offset[:, :, 0], offset[:, :, 1]) < reach)
        rank, slot = np.nonzero(close)
        return rank, offset[rank, slot]


def _on_a_body(who: np.ndarray, point: np.ndarray, xy: np.ndarray, table: NeighbourTable,
               radius: np.ndarray) -> np.ndarray:
    """Which obstacle points lie on the body of a node their robot hears (where that node says it is)."""
    geometric = table.geometric
    degree = np.diff(geometric.indptr)[who]
    pair_hit = np.repeat(np.arange(len(who)), degree)
    start = np.repeat(geometric.indptr[who] - np.cumsum(degree) + degree, degree)
    entry = start + np.arange(len(pair_hit))
    other = geometric.indices[entry]
    gap = np.hypot(*(point[pair_hit] - xy[other]).T) - radius[other]
    on_body = np.zeros(len(who), dtype=bool)
    on_body[pair_hit[gap <= BODY_MARGIN_M]] = True
    return on_body
