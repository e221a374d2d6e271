"""The local occupancy patch: what each robot has seen of the area with its own range sensors, around itself.

Each robot keeps its own grid over the area's bounding box (what a robot may know beforehand, never the map's
cells): a cell is *unknown* (0) until one of its beams crosses it (*free*, 1) or ends in it short of the sensors'
range (*occupied*, 2; a later beam ending there keeps it occupied). The patch is the ``P x P`` cells around the robot,
aligned with the area's axes, unknown beyond the box.
"""

from __future__ import annotations

import numpy as np

__all__ = ["FREE", "OCCUPIED", "UNKNOWN", "SeenMaps"]

UNKNOWN, FREE, OCCUPIED = 0, 1, 2


class SeenMaps:
    """The grids of what ``n`` robots have seen.

    Args:
        n: Number of robots.
        extent: ``(xmin, xmax, ymin, ymax)`` of the area, metres.
        cell: Side of a cell, metres.
        size: Side of the patch, cells.
    """

    def __init__(self, n: int, extent: tuple[float, float, float, float], cell: float, size: int) -> None:
        xmin, xmax, ymin, ymax = extent
        self.origin = np.array([xmin, ymin])
        self.cell = cell
        self.size = size
        self.shape = (max(1, int(np.ceil((ymax - ymin) / cell))), max(1, int(np.ceil((xmax - xmin) / cell))))
        self.grid = np.zeros((n, *self.shape), dtype=np.int8)

    def _cells(self, pts: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Rows, columns of points ``(..., 2)`` and whether they lie in the grid."""
        rc = np.floor((pts - self.origin) / self.cell).astype(np.int64)
        rows, cols = rc[..., 1], rc[..., 0]
        inside = (rows >= 0) & (rows < self.shape[0]) & (cols >= 0) & (cols < self.shape[1])
        return rows, cols, inside

    def update(self, rows: np.ndarray, xy: np.ndarray, heading: np.ndarray, scans: np.ndarray, angles: np.ndarray,
               sensor_range: float) -> None:
        """Add one ring of readings of the robots whose grids are ``rows`` ``(M,)``.

        Args:
            rows: Their grids ``(M,)``.
            xy: Their positions ``(M, 2)``.
            heading: Their headings ``(M,)``.
            scans: Their readings ``(M, beams)``.
            angles: The beams' angles from the heading.
            sensor_range: The sensors' range (a reading this long saw nothing).
        """
        samples = max(2, int(np.ceil(sensor_range / (0.5 * self.cell))) + 1)
        frac = np.linspace(0.0, 1.0, samples)[:-1]  # up to the reading, not its end
        a = heading[:, None] + angles[None, :]
        direction = np.stack([np.cos(a), np.sin(a)], axis=-1)  # (n, beams, 2)
        along = scans[:, :, None] * frac[None, None, :]  # (n, beams, samples)
        pts = xy[:, None, None, :] + along[..., None] * direction[:, :, None, :]
        robot = np.broadcast_to(rows[:, None, None], along.shape)
        r, c, inside = self._cells(pts)
        cell = self.grid[robot[inside], r[inside], c[inside]]
        self.grid[robot[inside], r[inside], c[inside]] = np.where(cell == OCCUPIED, OCCUPIED, FREE)
        hit = scans < sensor_range
        ends = xy[:, None, :] + scans[:, :, None] * direction
        r, c, inside = self._cells(ends)
        keep = hit & inside
        who = np.broadcast_to(rows[:, None], scans.shape)
        self.grid[who[keep], r[keep], c[keep]] = OCCUPIED

    def patch(self, grids: np.ndarray, xy: np.ndarray) -> np.ndarray:
        """The ``(M, P, P)`` patches of the robots whose grids are ``grids``, at ``xy`` (row 0 at the lowest ``y``)."""
        n, p = len(xy), self.size
        centre_r, centre_c, _ = self._cells(xy)
        off = np.arange(p) - p // 2
        rows = centre_r[:, None, None] + off[None, :, None]
        cols = centre_c[:, None, None] + off[None, None, :]
        rows, cols = np.broadcast_arrays(rows, cols)
        inside = (rows >= 0) & (rows < self.shape[0]) & (cols >= 0) & (cols < self.shape[1])
        out = np.zeros((n, p, p), dtype=np.int8)
        robot = np.broadcast_to(grids[:, None, None], rows.shape)
        out[inside] = self.grid[robot[inside], rows[inside], cols[inside]]
        return out
