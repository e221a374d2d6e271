"""The occupancy grid: the one representation of a 2-D world that every module reads.

Cells are stored with row 0 at the **bottom** (lowest y), so that cell ``(row, col)`` covers
``x in [ox + col*res, ox + (col+1)*res)`` and ``y in [oy + row*res, oy + (row+1)*res)`` where
``(ox, oy)`` is the map origin: the world position of the lower-left corner of cell ``(0, 0)``, exactly
as ROS ``map_server`` defines it. Images (whose row 0 is the top) are flipped once, on loading.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

__all__ = ["FREE", "OCCUPIED", "UNKNOWN", "OccupancyMap"]

FREE: int = 0
OCCUPIED: int = 1
UNKNOWN: int = -1


@dataclass(frozen=True, eq=False)
class OccupancyMap:
    """A 2-D occupancy grid in metres.

    Attributes:
        name: Short name (a built-in map's name or the YAML file's stem).
        resolution: Edge length of one cell in metres.
        origin: World ``(x, y)`` of the lower-left corner of cell ``(0, 0)``.
        cells: ``int8`` array ``(rows, cols)`` of ``FREE``, ``OCCUPIED`` or ``UNKNOWN``; row 0 is the bottom.
        source: Path of the YAML file the map came from, if any.
        licence: Licence note of the map's source, if known.
    """

    name: str
    resolution: float
    origin: tuple[float, float]
    cells: np.ndarray
    source: str | None = None
    licence: str | None = None
    _cache: dict = field(default_factory=dict, repr=False, compare=False)

    @property
    def shape(self) -> tuple[int, int]:
        """Grid shape ``(rows, cols)``."""
        return self.cells.shape  # type: ignore[return-value]

    @property
    def size_m(self) -> tuple[float, float]:
        """Width and height of the map in metres."""
        rows, cols = self.cells.shape
        return cols * self.resolution, rows * self.resolution

    @property
    def extent(self) -> tuple[float, float, float, float]:
        """``(xmin, xmax, ymin, ymax)`` of the map in world coordinates (for ``imshow``)."""
        w, h = self.size_m
        ox, oy = self.origin
        return ox, ox + w, oy, oy + h

    @property
    def free(self) -> np.ndarray:
        """Boolean mask of free cells."""
        return self.cells == FREE

    @property
    def blocked(self) -> np.ndarray:
        """Boolean mask of cells a robot may not enter: occupied or unknown (computed once, read-only)."""
        if "blocked" not in self._cache:
            mask = self.cells != FREE
            mask.flags.writeable = False
            self._cache["blocked"] = mask
        return self._cache["blocked"]

    def world_to_cell(self, xy: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Return ``(rows, cols)`` integer indices of the cells holding world points ``xy`` (shape ``(..., 2)``).

        Indices are not clipped: points outside the map give indices outside ``[0, rows) x [0, cols)``.
        """
        xy = np.asarray(xy, dtype=float)
        cols = np.floor((xy[..., 0] - self.origin[0]) / self.resolution).astype(np.int64)
        rows = np.floor((xy[..., 1] - self.origin[1]) / self.resolution).astype(np.int64)
        return rows, cols

    def cell_centres(self, rows: np.ndarray, cols: np.ndarray) -> np.ndarray:
        """World ``(x, y)`` of the centres of the given cells, shape ``(..., 2)``."""
        x = self.origin[0] + (np.asarray(cols) + 0.5) * self.resolution
        y = self.origin[1] + (np.asarray(rows) + 0.5) * self.resolution
        return np.stack([x, y], axis=-1)

    def inside(self, xy: np.ndarray) -> np.ndarray:
        """Boolean mask: which world points lie inside the map's rectangle."""
        rows, cols = self.world_to_cell(xy)
        r, c = self.shape
        return (rows >= 0) & (rows < r) & (cols >= 0) & (cols < c)

    def is_free(self, xy: np.ndarray) -> np.ndarray:
        """Boolean mask: which world points lie in a free cell (points outside the map are not free)."""
        rows, cols = self.world_to_cell(xy)
        ok = self.inside(xy)
        out = np.zeros(ok.shape, dtype=bool)
        out[ok] = self.cells[rows[ok], cols[ok]] == FREE
        return out
