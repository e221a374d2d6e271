"""The radio medium: who can hear whom, and how well, computed once per step and shared by every robot.

A medium turns positions into a symmetric neighbour table in CSR form (row ``i`` lists the nodes ``i`` can hear,
how far they are, and the link's quality: RSSI in dBm and packet delivery ratio). Controllers read only their own
row of it: what a real radio would hear. The sensors and the collision check reuse the medium's spatial search
(the table's :attr:`NeighbourTable.geometric` view: every node within a radius, walls or not), so the spatial
index is built once per step.

Three models register by name (``radio.model``); all share one link budget (:mod:`amronet.engine.propagation`),
calibrated so that without walls and shadowing the median link reaches exactly ``r_c``:

* ``unit-disk`` (the paper's): linked exactly when at most ``r_c`` apart, through any wall. Links carry the RSSI
  of the log-distance law without shadowing, so location-free rules can run on it too.
* ``log-distance``: path loss with exponent ``n`` and spatially correlated log-normal shadowing
  (:mod:`amronet.engine.shadowing`); walls do not count.
* ``multi-wall`` (COST 231 / Motley-Keenan): log-distance plus ``wall_db`` per wall crossed
  (:mod:`amronet.engine.walls`), with optional shadowing.

A link exists when its RSSI is at or above the usable threshold (delivery ratio 0.9). With ``packet_loss`` on, an
existing link with delivery ratio ``p`` drops out of a step's table with probability ``1 - p`` (one draw per link
and step, from a stream of its own so that the controllers' draws are unchanged).

New models subclass :class:`RadioMedium`, override :meth:`RadioMedium.margins` (link quality) or
:meth:`RadioMedium.keep` (a rule that drops links) and register with ``@MEDIA.register(name)``.
"""

from __future__ import annotations

from typing import ClassVar

import numpy as np
from numba import njit

from amronet.engine.coverage import CoverageArea
from amronet.engine.hearing import Hearing, best_margin_grid, cell_field, heard_box, heard_cells, link_margin
from amronet.engine.neighbours import GroupIds, neighbour_csr_checked
from amronet.engine.propagation import LinkBudget, delivery_ratio
from amronet.engine.shadowing import ShadowingField, _cell_value
from amronet.engine.table import NeighbourTable
from amronet.registry import Registry
from amronet.world.occupancy import OccupancyMap

__all__ = ["DEFAULT_WALL_DB", "MEDIA", "LogDistance", "MultiWall", "NeighbourTable", "RadioMedium", "UnitDisk",
           "make_medium"]


_BOX_CACHE_BYTES = 256 * 2**20
"""Above this many cells of boxes, a medium keeps none (coverage is then computed afresh each time)."""

DEFAULT_WALL_DB: float = 6.9
"""Loss per wall crossed when none is given: COST 231's heavy internal wall (dB)."""


@njit(cache=True)
def _mirror(indptr, indices):  # pragma: no cover - numba
    """For every entry ``(i, j)`` of a symmetric CSR with sorted rows, the position of its entry ``(j, i)``.

    Visiting the rows in order, the entries ``(j, i)`` with ``i < j`` of row ``j`` come up in column order, so a
    cursor per row finds each one in constant time.
    """
    n = indptr.shape[0] - 1
    out = np.empty(indices.shape[0], np.int64)
    cursor = indptr[:-1].copy()
    for i in range(n):
        for e in range(indptr[i], indptr[i + 1]):
            j = indices[e]
            if j > i:
                f = cursor[j]
                cursor[j] = f + 1
                out[e] = f
                out[f] = e
    return out


@njit(cache=True, inline="always")
def _find(indptr, indices, i, j):  # pragma: no cover - numba
    """Position of entry ``(i, j)`` in a CSR with sorted rows, -1 if absent."""
    lo = indptr[i]
    hi = indptr[i + 1]
    while lo < hi:
        mid = (lo + hi) // 2
        if indices[mid] < j:
            lo = mid + 1
        else:
            hi = mid
    return lo if lo < indptr[i + 1] and indices[lo] == j else -1


@njit(cache=True)
def _candidate_margins(xy, indptr, indices, dist, prev_xy, prev_indptr, prev_indices, prev_margin, r_c, n10, wall_db,
                       walls, jump, ox, oy, res, shadow, sx0, sy0, sh, corr,
                       clip):  # pragma: no cover - numba
    """Margin of every candidate link, computed once per pair (walking from the lower id) and mirrored.

    A pair whose two ends stand exactly where they stood in the previous table (``prev_*``) and were a candidate
    there takes its margin from it: a margin depends on the two positions alone, so it is the same number.
    """
    out = np.empty(indices.shape[0])
    cursor = indptr[:-1].copy()  # see _mirror
    n_prev = prev_xy.shape[0]
    for i in range(indptr.shape[0] - 1):
        xa = xy[i, 0]
        ya = xy[i, 1]
        still_i = i < n_prev and xa == prev_xy[i, 0] and ya == prev_xy[i, 1]
        sa = _cell_value(shadow, sx0, sy0, sh, xa, ya) if clip > 0.0 else 0.0
        for e in range(indptr[i], indptr[i + 1]):
            j = indices[e]
            if j < i:
                continue
            xb = xy[j, 0]
            yb = xy[j, 1]
            f = -1
            if still_i and j < n_prev and xb == prev_xy[j, 0] and yb == prev_xy[j, 1]:
                f = _find(prev_indptr, prev_indices, i, j)
            if f >= 0:
                m = prev_margin[f]
            else:
                sb = _cell_value(shadow, sx0, sy0, sh, xb, yb) if clip > 0.0 else 0.0
                m = link_margin(xa, ya, xb, yb, dist[e], sa, sb, 0.0, r_c, n10, wall_db, walls, jump, ox, oy, res,
                                shadow, sx0, sy0, sh, corr, clip)
            out[e] = m
            f = cursor[j]
            cursor[j] = f + 1
            out[f] = m
    return out


@njit(cache=True)
def _keep(indptr, indices, dist, margin, keep):  # pragma: no cover - numba
    """The CSR arrays ``(indptr, indices, dist, margin)`` of the entries in ``keep``."""
    n = indptr.shape[0] - 1
    m = 0
    for e in range(keep.shape[0]):
        if keep[e]:
            m += 1
    out_ptr = np.zeros(n + 1, np.int64)
    out_idx = np.empty(m, indices.dtype)
    out_dist = np.empty(m)
    out_margin = np.empty(m)
    k = 0
    for i in range(n):
        for e in range(indptr[i], indptr[i + 1]):
            if keep[e]:
                out_idx[k] = indices[e]
                out_dist[k] = dist[e]
                out_margin[k] = margin[e]
                k += 1
        out_ptr[i + 1] = k
    return out_ptr, out_idx, out_dist, out_margin


class RadioMedium:
    """Base class of radio propagation models.

    Args:
        budget: The link budget (range, power, path loss, walls, shadowing), or just ``r_c`` (the model's defaults
            for the rest: see :data:`DEFAULT_WALL_DB`).
        omap: The map (walls; the shadowing field's extent). Needed by models with walls or shadowing.
        rng: The run's generator. A model with shadowing or packet loss spawns its own child streams from it
            (``rng.spawn``), which leaves the run's own stream untouched: the same seed places the robots the same
            way under every model.
        packet_loss: Drop each link in each step with probability one minus its delivery ratio.

    Attributes:
        budget: As given.
        shadowing: The run's shadowing field (``None`` without shadowing).
    """

    name = "abstract"
    default_exponent: ClassVar[float] = 2.5
    """Path-loss exponent when the scenario gives none."""
    default_shadowing_db: ClassVar[float] = 0.0
    """Shadowing when the scenario gives none."""
    uses_walls: ClassVar[bool] = False
    uses_shadowing: ClassVar[bool] = False

    def __init__(self, budget: LinkBudget | float, omap: OccupancyMap | None = None,
                 rng: np.random.Generator | None = None, packet_loss: bool = False) -> None:
        if not isinstance(budget, LinkBudget):  # just r_c: the model's defaults for the rest
            wall_db = DEFAULT_WALL_DB if self.uses_walls else 0.0
            budget = LinkBudget(r_c=float(budget), exponent=self.default_exponent,
                                shadowing_db=self.default_shadowing_db, wall_db=wall_db)
        self.budget = budget
        self.omap = omap
        self.packet_loss = bool(packet_loss)
        children = rng.spawn(2) if rng is not None and (self.uses_shadowing or packet_loss) else None
        self.shadowing: ShadowingField | None = None
        if self.uses_shadowing and budget.shadowing_db > 0:
            if omap is None or children is None:
                raise ValueError(f"the {self.name} model with shadowing needs the map and the run's generator")
            self.shadowing = ShadowingField(omap.extent, budget.shadowing_db, budget.shadowing_corr_m, children[0])
        self._loss_rng = children[1] if packet_loss and children is not None else None
        if packet_loss and self._loss_rng is None:
            raise ValueError("packet loss needs the run's generator")
        self._groups: GroupIds | None = None
        """The group ids last checked (:meth:`_group_ids`)."""
        self._grids: dict[tuple, tuple] = {}
        self._boxes: dict[int, tuple] = {}
        """Per coverage area, the node positions met lately: ``[cells heard or None, first call, last call]``. A
        position met again two calls after it was first met (a node that stays) keeps its cells, so a step in
        which few nodes moved recomputes only theirs. Cells depend on a node and a cell alone: the result is the
        same with or without the cache."""
        self.hearing = Hearing.from_budget(budget if self.uses_walls else _no_walls(budget), omap, self.shadowing)

    @property
    def r_c(self) -> float:
        """The median range without walls and shadowing (the paper's communication radius)."""
        return self.budget.r_c

    @property
    def reach(self) -> float:
        """The radius within which links are searched: no link is longer."""
        return self.hearing.reach if self.shadowing is not None else self.budget.r_c

    def margins(self, xy: np.ndarray, indptr: np.ndarray, indices: np.ndarray, dist: np.ndarray) -> np.ndarray | None:
        """Margin over the threshold of every candidate link (CSR order, symmetric).

        ``None``: the distances decide (every candidate is a link and margins follow from the distance).
        """
        return None

    def keep(self, xy: np.ndarray, indptr: np.ndarray, indices: np.ndarray, dist: np.ndarray) -> np.ndarray | None:
        """Mask of candidate links (CSR order) a model drops by a rule of its own; ``None`` keeps them. Symmetric."""
        return None

    def update(self, xy: np.ndarray, groups: np.ndarray | None = None, silent: np.ndarray | None = None
               ) -> NeighbourTable:
        """Build this step's neighbour table from all robot positions ``(N, 2)`` (of several runs: ``groups``).

        ``silent``: mask of nodes that send nothing (failed nodes): they have no links, but stay in the geometric
        table (:attr:`NeighbourTable.geometric`) that body sensors and collisions read.
        """
        xy = np.array(xy, dtype=float)
        if xy.ndim != 2 or xy.shape[1] != 2:
            raise ValueError(f"xy must have shape (N, 2), got {xy.shape}")
        b = self.budget
        indptr, indices, dist = neighbour_csr_checked(xy, self.reach, self._group_ids(groups, len(xy)))
        margin = self.margins(xy, indptr, indices, dist)
        candidates = None
        keep = None if margin is None else margin >= 0.0
        extra = self.keep(xy, indptr, indices, dist)
        if extra is not None:
            keep = extra if keep is None else keep & extra
        if silent is not None and silent.any():
            rows = np.repeat(np.arange(len(xy)), np.diff(indptr))
            heard = ~(silent[rows] | silent[indices])
            keep = heard if keep is None else keep & heard
        if self.packet_loss:
            lost = self._losses(indptr, indices, b.margin_db(dist) if margin is None else margin)
            keep = ~lost if keep is None else keep & ~lost
        if keep is not None and not keep.all():
            candidates = NeighbourTable(xy=xy, r=self.reach, indptr=indptr, indices=indices, dist=dist,
                                        groups=groups, threshold_dbm=b.threshold_dbm, exponent=b.exponent,
                                        link_margin=margin)
            full = b.margin_db(dist) if margin is None else margin
            indptr, indices, dist, kept = _keep(indptr, indices, dist, full, keep)
            margin = None if margin is None else kept
        # by position, in the order of the fields (keywords cost more than the rest of a small table's update)
        return NeighbourTable(xy, self.reach, indptr, indices, dist, groups, b.threshold_dbm, margin, b.exponent,
                              candidates)

    @property
    def keeps_every_pair(self) -> bool:
        """Whether a table is every pair the search finds within :attr:`reach`, as it is (the unit disk).

        So it is for a single run without failed nodes when the model has no margins and drops no link by a rule or
        by loss: :meth:`update` then builds :meth:`plain_table`.
        """
        return (type(self).margins is RadioMedium.margins and type(self).keep is RadioMedium.keep
                and not self.packet_loss)

    def plain_table(self, xy: np.ndarray, indptr: np.ndarray, indices: np.ndarray, dist: np.ndarray,
                    groups: np.ndarray | None = None) -> NeighbourTable:
        """The table :meth:`update` builds of ``xy`` (of runs ``groups``) under :attr:`keeps_every_pair`, none silent.

        For a compiled caller that searched itself (:func:`~amronet.engine.neighbours.search_kernel` within
        :attr:`reach`, of these groups) and found this CSR.
        """
        b = self.budget
        return NeighbourTable(xy, self.reach, indptr, indices, dist, groups, b.threshold_dbm, None, b.exponent, None)

    def _group_ids(self, groups: np.ndarray | None, n: int) -> GroupIds:
        """``groups`` checked for ``n`` points; kept while the same array (a loop's, for all its steps) comes back."""
        known = self._groups
        if known is None or known.source is not groups or len(known.ids) != n:
            known = self._groups = GroupIds.of(groups, n)
        return known

    def _losses(self, indptr: np.ndarray, indices: np.ndarray, margin: np.ndarray) -> np.ndarray:
        """Which entries drop out this step: one draw per link (pair), shared by its two entries."""
        rows = np.repeat(np.arange(len(indptr) - 1), np.diff(indptr))
        upper = np.flatnonzero(indices > rows)
        mirror = _mirror(indptr, indices)
        lost = np.zeros(len(indices), dtype=bool)
        drop = self._loss_rng.random(len(upper)) >= delivery_ratio(margin[upper])
        lost[upper] = drop
        lost[mirror[upper]] = drop
        return lost

    # -- where the nodes are heard ---------------------------------------------------------------------------
    def run_coverages(self, area: CoverageArea, xy: np.ndarray, network: np.ndarray, linked: np.ndarray,
                      blocks: np.ndarray, method: str = "raster") -> list[tuple[float, float]] | None:
        """Per run of a batch, :meth:`coverage` of its ``network`` nodes and of its ``linked`` ones, or ``None``.

        Args:
            area: The area.
            xy: Every run's robots ``(N, 2)``, a run's in a block of rows.
            network: Mask ``(N,)`` of the covering nodes.
            linked: Mask ``(N,)`` of the covering nodes with a path to a base station.
            blocks: ``(runs, 2)`` first and past-the-last row of each run.
            method: The coverage method.

        Returns:
            ``(coverage, linked coverage)`` per run, the same numbers as :meth:`coverage`; ``None`` where the model
            has no faster way than run by run (the caller then asks :meth:`coverage` run by run).
        """
        return None

    def coverage(self, area: CoverageArea, xy: np.ndarray, method: str = "raster") -> float:
        """Coverage under this radio: the fraction of ``area`` where a receiver would hear a node of ``xy``.

        For the unit disk this is Eq. (1) (:meth:`CoverageArea.fraction`, either method). Other models decide cell
        by cell at the cell centres (the raster method).

        Raises:
            ValueError: ``method`` is ``exact`` for a model other than the unit disk.
        """
        if method != "raster":
            raise ValueError(f"coverage method {method!r} is only defined for the unit disk; use raster")
        return self._heard(area, xy).sum() / area.n_cells

    def covered_mask(self, area: CoverageArea, xy: np.ndarray) -> np.ndarray:
        """Boolean mask of the cells of ``area`` where a receiver would hear a node of ``xy``."""
        return self._heard(area, xy)

    def _heard(self, area: CoverageArea, xy: np.ndarray) -> np.ndarray:
        xy = np.ascontiguousarray(xy, dtype=float).reshape(-1, 2)
        if not np.isfinite(xy).all():
            raise ValueError("xy must be finite")
        covered = np.zeros(area.mask.shape, dtype=bool)
        grid = self._grid(area.omap)
        args = self.hearing.args()
        cache = self._boxes.get(id(area))
        if cache is None or cache[0] is not area:  # a new area: a fresh cache of boxes (see _boxes)
            cache = self._boxes[id(area)] = (area, {}, [0])
        _, boxes, calls = cache
        calls[0] += 1
        now = calls[0]
        size = 0
        moving = []
        for k, key in enumerate(map(tuple, xy.tolist())):
            entry = boxes.get(key)
            if entry is None:  # a position not met before: marked with the others below
                boxes[key] = [None, now, now]
                moving.append(k)
                continue
            entry[2] = now
            if entry[0] is None and entry[1] <= now - 2:  # met two calls ago or earlier: it stays, keep its cells
                entry[0] = heard_box(key[0], key[1], area.mask, *grid[:3], self.reach, *grid[3:], *args)
            if entry[0] is None:
                moving.append(k)
                continue
            i0, j0, piece = entry[0]
            size += piece.size
            covered[i0:i0 + piece.shape[0], j0:j0 + piece.shape[1]] |= piece
        if moving:  # one pass that skips the cells covered already
            heard_cells(xy[moving], area.mask, *grid[:3], self.reach, covered, *grid[3:], *args)
        for key in [k for k, e in boxes.items() if e[2] < now - 2 or size > _BOX_CACHE_BYTES]:
            del boxes[key]  # positions not met in the last three calls
        return covered

    def _grid(self, omap: OccupancyMap) -> tuple:
        """``(gox, goy, gres, cell_s, block_s)`` of a map's cells for the kernels, cached per grid."""
        key = (omap.shape, float(omap.origin[0]), float(omap.origin[1]), float(omap.resolution))
        if key not in self._grids:
            h = self.hearing
            self._grids[key] = (*key[1:], *cell_field(omap.shape, *key[1:], h.shadow, h.sx0, h.sy0, h.sh, h.clip))
        return self._grids[key]

    def signal_dbm(self, omap: OccupancyMap, xy: np.ndarray, floor_db: float = -30.0) -> np.ndarray:
        """Best RSSI (dBm) at every cell centre of ``omap`` over the nodes ``xy``.

        NaN where every node is more than ``-floor_db`` dB below the usable threshold (or there are no nodes).
        """
        xy = np.ascontiguousarray(xy, dtype=float).reshape(-1, 2)
        if not np.isfinite(xy).all():
            raise ValueError("xy must be finite")
        out = np.full(omap.shape, -np.inf)
        grid = self._grid(omap)
        best_margin_grid(xy, *grid[:3], out, float(floor_db), *grid[3:], *self.hearing.args())
        out[~np.isfinite(out)] = np.nan
        return out + self.budget.threshold_dbm


def _no_walls(budget: LinkBudget) -> LinkBudget:
    return LinkBudget(r_c=budget.r_c, tx_dbm=budget.tx_dbm, pl0_db=budget.pl0_db, exponent=budget.exponent,
                      wall_db=0.0, shadowing_db=budget.shadowing_db, shadowing_corr_m=budget.shadowing_corr_m,
                      shadowing_clip=budget.shadowing_clip)


MEDIA: Registry[type[RadioMedium]] = Registry("radio model")
"""Radio models by name; a model registers itself with ``@MEDIA.register(name)``."""


@MEDIA.register("unit-disk")
class UnitDisk(RadioMedium):
    """Unit disk graph: two nodes are linked exactly when their distance is at most ``r_c`` (the paper's)."""

    def coverage(self, area: CoverageArea, xy: np.ndarray, method: str = "raster") -> float:
        """Eq. (1) of the paper, by either method (:meth:`CoverageArea.fraction`)."""
        return area.fraction(xy, self.r_c, method=method)

    def covered_mask(self, area: CoverageArea, xy: np.ndarray) -> np.ndarray:
        """The cells whose centre lies within ``r_c`` of a node (:meth:`CoverageArea.covered_mask`)."""
        return area.covered_mask(xy, self.r_c)

    def run_coverages(self, area: CoverageArea, xy: np.ndarray, network: np.ndarray, linked: np.ndarray,
                      blocks: np.ndarray, method: str = "raster") -> list[tuple[float, float]] | None:
        """The raster method in one compiled call for all runs (:meth:`CoverageArea.run_fractions`)."""
        return area.run_fractions(xy, network, linked, blocks, self.r_c) if method == "raster" else None


_NO_PREVIOUS = (np.zeros((0, 2)), np.zeros(1, np.int64), np.zeros(0, np.int32), np.zeros(0))


class _PathLoss(RadioMedium):
    """Models whose links are decided by their margin: distance, shadowing and, with walls, the walls crossed.

    The medium remembers its last candidate table: links between nodes that have not moved since keep their margin
    (most of a deployed network stands still while agents and explorers move).
    """

    uses_shadowing = True
    _previous: tuple | None = None

    def margins(self, xy: np.ndarray, indptr: np.ndarray, indices: np.ndarray, dist: np.ndarray) -> np.ndarray | None:
        h = self.hearing
        if h.clip == 0.0 and h.wall_db == 0.0:
            return None  # no shadowing, no walls: the unit disk, decided by distance
        prev = self._previous if self._previous is not None else _NO_PREVIOUS
        margin = _candidate_margins(xy, indptr, indices, dist, *prev, *h.args())
        self._previous = (xy, indptr, indices, margin)
        return margin


@MEDIA.register("log-distance")
class LogDistance(_PathLoss):
    """Log-distance path loss with spatially correlated log-normal shadowing (Stage's ``model_wifi``, ns-3)."""

    default_exponent = 2.5
    default_shadowing_db = 5.0


@MEDIA.register("multi-wall")
class MultiWall(_PathLoss):
    """COST 231 multi-wall (Motley-Keenan): log-distance plus a fixed loss per wall crossed, optional shadowing."""

    default_exponent = 2.0
    default_shadowing_db = 0.0
    uses_walls = True


def make_medium(model: str, budget: LinkBudget | float, omap: OccupancyMap | None = None,
                rng: np.random.Generator | None = None, packet_loss: bool = False) -> RadioMedium:
    """Instantiate the radio medium registered as ``model``.

    Args:
        model: The registered name (``radio.model``).
        budget: The link budget, or just ``r_c`` (the model's defaults for the rest).
        omap: The map (walls, the shadowing field's extent).
        rng: The run's generator (shadowing, packet loss).
        packet_loss: Drop links per step by their delivery ratio.

    Raises:
        ScenarioError: ``model`` is unknown (field ``radio.model``).
    """
    return MEDIA.lookup(model, "radio.model")(budget, omap=omap, rng=rng, packet_loss=packet_loss)
