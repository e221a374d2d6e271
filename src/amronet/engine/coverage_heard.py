"""Coverage and signal maps under a radio model: the cells a receiver would hear, by the model's margin kernel.

:class:`HeardCells` runs a model's kernels (:mod:`amronet.engine.margin_kernels`) over a map's cells for the radio
medium (:mod:`amronet.engine.radio`): which cells of a coverage area some node is heard in, and the best margin per
cell. It keeps the union of the cells heard from the nodes of the last call (:mod:`amronet.engine.coverage_union`),
so a call in which few nodes moved decides only the cells they change.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from amronet.engine.coverage import CoverageArea
from amronet.engine.coverage_union import BYTES_PER_CELL, HeardUnion, Mark, block_grid, full_window
from amronet.engine.hearing import HearingInputs, cells_of
from amronet.engine.margin_kernels import MarginKernels
from amronet.world.occupancy import OccupancyMap

__all__ = ["HeardCells"]

_CACHE_BYTES = 256 * 2**20
"""The unions a medium keeps take at most this many bytes over all areas (the least recently used is dropped
first; an area whose one union would take more is computed afresh each time)."""

_UNIONS_PER_AREA = 2
"""Unions kept per coverage area: one per set of nodes asked about in turn (a run's nodes, its connected ones)."""

_FEW = 8
"""When more members than this leave a union, and more than half of them, it is cleared and built again."""

_NO_OWNER = np.zeros((0, 0), np.int32)
_NO_KEYS = np.zeros(0, np.int32)


class _AreaCache:
    """What :class:`HeardCells` keeps of one coverage area and reach: its unions."""

    __slots__ = ("area", "reach", "unions")

    def __init__(self, area: CoverageArea, reach: float) -> None:
        self.area = area
        self.reach = reach
        self.unions: list[HeardUnion] = []


class HeardCells:
    """The cells a radio's receivers hear, for coverage and the signal map.

    Args:
        hearing: The radio's inputs.
        kernels: The kernels of its margin kernel.
        cache_bytes: The most the unions take (see ``areas``).

    Attributes:
        areas: Per coverage area, up to two :class:`~amronet.engine.coverage_union.HeardUnion`: the cells heard
            from the nodes of a call, with the node that marked each cell first. A call brings the union closest
            to its nodes up to date (a node that left decides again only the cells it marked first, a new one
            marks only the cells still uncovered) and copies it. When a set of nodes asks again for positions it
            dropped from a union at its last call (two sets asked about in turn: a run's nodes and its connected
            ones), it gets a union of its own: a copy of that union, brought up to date. Cells depend on a node
            and a cell alone: the result is the same with or without the unions.
    """

    def __init__(self, hearing: HearingInputs, kernels: MarginKernels, cache_bytes: int = _CACHE_BYTES) -> None:
        self.plain = hearing.plain()
        self.hearing = hearing
        self.kernels = kernels
        self.cache_bytes = cache_bytes
        self.areas: dict[int, _AreaCache] = {}
        self._clock = 0
        self._cells: dict[tuple, tuple] = {}

    def forget(self) -> None:
        """Drop every union (the next calls start afresh)."""
        self.areas.clear()

    def covered(self, area: CoverageArea, xy: np.ndarray, reach: float) -> np.ndarray:
        """Mask of the cells of ``area`` heard from a node of ``xy`` ``(N, 2)``; no link is longer than ``reach``.

        Raises:
            ValueError: ``xy`` has non-finite coordinates.
        """
        xy = _finite(xy)
        reach = float(reach)
        memo = self.areas.get(id(area))
        if memo is None or memo.area is not area or memo.reach != reach:  # a new area: start afresh (see areas)
            memo = self.areas[id(area)] = _AreaCache(area, reach)
        mark = self._marker(area, reach)
        union = self._union(memo, dict.fromkeys(map(tuple, xy.tolist())), mark) if len(xy) else None
        if union is not None:
            return union.union.copy()
        covered = np.zeros(area.mask.shape, dtype=bool)  # no node, or no room for a union: one pass
        mark(xy, _NO_KEYS, area.mask, covered, _NO_OWNER, full_window(covered.shape), block_grid(covered.shape))
        return covered

    def _union(self, memo: _AreaCache, positions: dict, mark: Mark) -> HeardUnion | None:
        """The union of ``memo`` closest to the nodes at ``positions``, brought up to date."""
        best, gone, new = None, [], list(positions)
        for union in memo.unions:
            g, n = union.changes(positions)
            if best is None or len(g) + len(n) < len(gone) + len(new):
                best, gone, new = union, g, n
        # most of its members leave: cheaper to start again
        afresh = best is None or (len(gone) > _FEW and 2 * len(gone) > len(best.members))
        if afresh or any(key in best.dropped for key in new):  # a new union, if there is room for one
            spare = self._spare(memo)
            if spare is not None and not afresh:  # a second set of nodes: it starts from the closest union
                spare.become(best)
                best = spare
                gone, new = best.changes(positions)
            elif spare is not None:
                best, gone, new = spare, [], list(positions)
            elif best is None:
                return None
            elif afresh:
                best = min(memo.unions, key=lambda u: u.used)
                best.clear()
                gone, new = [], list(positions)
        self._clock += 1
        best.used = self._clock
        try:
            best.update(gone, new, memo.area.mask, mark)
        except BaseException:  # interrupted half way (Ctrl-C): the union is dropped, never left wrong
            memo.unions.remove(best)
            raise
        return best

    def _spare(self, memo: _AreaCache) -> HeardUnion | None:
        """A new union for ``memo``'s area, room made by dropping the least recently used of other areas'."""
        shape = memo.area.mask.shape
        need = shape[0] * shape[1] * BYTES_PER_CELL
        if len(memo.unions) >= _UNIONS_PER_AREA or need > self.cache_bytes:
            return None
        others = sorted((u.used, id(u), m) for m in self.areas.values() if m is not memo for u in m.unions)
        kept = sum(u.nbytes for m in self.areas.values() for u in m.unions)
        for used, uid, m in others:
            if kept + need <= self.cache_bytes:
                break
            gone = next(u for u in m.unions if u.used == used and id(u) == uid)
            m.unions.remove(gone)
            kept -= gone.nbytes
        if kept + need > self.cache_bytes:
            return None
        omap = memo.area.omap
        union = HeardUnion(shape, lambda xy: _boxes(omap, xy, memo.reach))
        memo.unions.append(union)
        return union

    def _marker(self, area: CoverageArea, reach: float) -> Mark:
        """:func:`~amronet.engine.hearing.heard_cells` on ``area``'s grid with ``reach``."""
        cells, h, kernel = self.cells(area.omap), self.plain, self.kernels.heard_cells

        def mark(xy: np.ndarray, keys: np.ndarray, mask: np.ndarray, covered: np.ndarray, owner: np.ndarray,
                 window: tuple[int, int, int, int], blocks: np.ndarray) -> int:
            return kernel(xy, keys, mask, cells, reach, covered, owner, window, h, blocks)
        return mark

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
        """The kernels' :class:`~amronet.engine.cell_boxes.Cells` of a map's grid as a plain tuple, cached per grid."""
        key = (omap.shape, float(omap.origin[0]), float(omap.origin[1]), float(omap.resolution))
        if key not in self._cells:
            self._cells[key] = tuple(cells_of(*key, self.hearing.clip, self.hearing.field))
        return self._cells[key]


def _boxes(omap: OccupancyMap, xy: np.ndarray, reach: float) -> np.ndarray:
    """Rows ``(i0, i1, j0, j1)`` ``(N, 4)`` of cells of ``omap`` that hold every cell within ``reach`` of ``xy``.

    A cell more on each side than :func:`~amronet.engine.hearing.heard_cells` looks at, clipped to the grid.
    """
    res, (ox, oy), (rows, cols) = float(omap.resolution), omap.origin, omap.shape
    reach = min(reach, (rows + cols) * res)  # an infinite reach: the whole map
    side = np.array([-1.0, 1.0])
    i = np.floor((xy[:, 1:2] + side * reach - oy) / res) + side
    j = np.floor((xy[:, 0:1] + side * reach - ox) / res) + side
    return np.hstack([np.clip(i, 0, rows - 1), np.clip(j, 0, cols - 1)]).astype(np.intp)


def _finite(xy: np.ndarray) -> np.ndarray:
    xy = np.ascontiguousarray(xy, dtype=float).reshape(-1, 2)
    if not np.isfinite(xy).all():
        raise ValueError("xy must be finite")
    return xy
