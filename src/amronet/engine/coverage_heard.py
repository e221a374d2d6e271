"""Coverage and signal maps under a radio model: the cells a receiver would hear, by the model's margin kernel.

:class:`HeardCells` runs a model's kernels (:mod:`amronet.engine.margin_kernels`) over a map's cells for the radio
medium (:mod:`amronet.engine.radio`): which cells of a coverage area some node is heard in, and the best margin per
cell. It keeps the cells of nodes that stay where they were, so a step in which few nodes moved recomputes only
theirs.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from amronet.engine.coverage import CoverageArea
from amronet.engine.hearing import HearingInputs, cells_of
from amronet.engine.margin_kernels import MarginKernels
from amronet.world.occupancy import OccupancyMap

__all__ = ["HeardCells"]

_BOX_CACHE_BYTES = 256 * 2**20
"""Above this many cells of boxes, a medium keeps none (coverage is then computed afresh each time)."""


class HeardCells:
    """The cells a radio's receivers hear, for coverage and the signal map.

    Args:
        hearing: The radio's inputs.
        kernels: The kernels of its margin kernel.

    Attributes:
        boxes: Per coverage area, the node positions met lately: ``[cells heard or None, first call, last call]``.
            A position met again two calls after it was first met (a node that stays) keeps its cells. Cells depend
            on a node and a cell alone: the result is the same with or without the cache.
    """

    def __init__(self, hearing: HearingInputs, kernels: MarginKernels) -> None:
        self.plain = hearing.plain()
        self.hearing = hearing
        self.kernels = kernels
        self.boxes: dict[int, tuple] = {}
        self._cells: dict[tuple, tuple] = {}

    def covered(self, area: CoverageArea, xy: np.ndarray, reach: float) -> np.ndarray:
        """Mask of the cells of ``area`` heard from a node of ``xy`` ``(N, 2)``; no link is longer than ``reach``.

        Raises:
            ValueError: ``xy`` has non-finite coordinates.
        """
        xy = _finite(xy)
        covered = np.zeros(area.mask.shape, dtype=bool)
        cells, h, k = self.cells(area.omap), self.plain, self.kernels
        cache = self.boxes.get(id(area))
        if cache is None or cache[0] is not area:  # a new area: a fresh cache of boxes (see boxes)
            cache = self.boxes[id(area)] = (area, {}, [0])
        _, boxes, calls = cache
        calls[0] += 1
        now = calls[0]
        size = 0
        moving = []
        for n, key in enumerate(map(tuple, xy.tolist())):
            entry = boxes.get(key)
            if entry is None:  # a position not met before: marked with the others below
                boxes[key] = [None, now, now]
                moving.append(n)
                continue
            entry[2] = now
            if entry[0] is None and entry[1] <= now - 2:  # met two calls ago or earlier: it stays, keep its cells
                entry[0] = k.heard_box(key[0], key[1], area.mask, cells, reach, h)
            if entry[0] is None:
                moving.append(n)
                continue
            i0, j0, piece = entry[0]
            size += piece.size
            covered[i0:i0 + piece.shape[0], j0:j0 + piece.shape[1]] |= piece
        if moving:  # one pass that skips the cells covered already
            k.heard_cells(xy[moving], area.mask, cells, reach, covered, h)
        for key in [key for key, e in boxes.items() if e[2] < now - 2 or size > _BOX_CACHE_BYTES]:
            del boxes[key]  # positions not met in the last three calls
        return covered

    def best_margins(self, omap: OccupancyMap, xy: np.ndarray, floor_db: float, reach: float,
                     progress: Callable[[int, int], None] | None = None) -> np.ndarray:
        """Best margin (dB) at every cell centre of ``omap`` over the nodes ``xy``; ``-inf`` below ``floor_db``.

        No margin at or above ``floor_db`` is farther than ``reach`` (which may be infinite). With ``progress``, the
        nodes go to the kernel in about a hundred slices, and ``progress(done, total)`` is called after each (the
        maximum over the nodes is the same whatever the slices).

        Raises:
            ValueError: ``xy`` has non-finite coordinates.
        """
        xy = _finite(xy)
        out = np.full(omap.shape, -np.inf)
        n = len(xy)
        step = max(n, 1) if progress is None else max(-(-n // 100), 1)
        for k in range(0, n, step):
            self.kernels.best_margin_grid(xy[k:k + step], self.cells(omap), out, float(floor_db), float(reach),
                                          self.plain)
            if progress is not None:
                progress(min(k + step, n), n)
        return out

    @staticmethod
    def cells_in_reach(omap: OccupancyMap, xy: np.ndarray, reach: float) -> int:
        """How many cells of ``omap`` the signal kernels visit for the nodes ``xy``: each node's box of ``reach``.

        The work of :meth:`best_margins`, for a guard to estimate before it starts.
        """
        xy = _finite(xy)
        res, (ox, oy), (rows, cols) = float(omap.resolution), omap.origin, omap.shape
        reach = min(float(reach), (rows + cols) * res)  # an infinite reach: the whole map
        i0 = np.clip(np.floor((xy[:, 1] - reach - oy) / res), 0, rows)
        i1 = np.clip(np.floor((xy[:, 1] + reach - oy) / res), -1, rows - 1)
        j0 = np.clip(np.floor((xy[:, 0] - reach - ox) / res), 0, cols)
        j1 = np.clip(np.floor((xy[:, 0] + reach - ox) / res), -1, cols - 1)
        return int((np.maximum(i1 - i0 + 1, 0) * np.maximum(j1 - j0 + 1, 0)).sum())

    def cells(self, omap: OccupancyMap) -> tuple:
        """The kernels' :class:`~amronet.engine.hearing.Cells` of a map's grid as a plain tuple, cached per grid."""
        key = (omap.shape, float(omap.origin[0]), float(omap.origin[1]), float(omap.resolution))
        if key not in self._cells:
            self._cells[key] = tuple(cells_of(*key, self.hearing))
        return self._cells[key]


def _finite(xy: np.ndarray) -> np.ndarray:
    xy = np.ascontiguousarray(xy, dtype=float).reshape(-1, 2)
    if not np.isfinite(xy).all():
        raise ValueError("xy must be finite")
    return xy
