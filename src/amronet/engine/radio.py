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

A link exists when its margin over the usable threshold (delivery ratio 0.9) is ``>= 0``. With ``packet_loss``
on, an existing link with delivery ratio ``p`` drops out of a step's table with probability ``1 - p`` (one draw per
link and step, from a stream of its own so that the controllers' draws are unchanged).

**A new model** is one class, one registry line and its margin kernel: a compiled function
``margin(xa, ya, xb, yb, d, sa, sb, floor_db, h)`` giving the margin (dB over the threshold) of the link between
two points ``d`` apart, for the radio's :class:`~amronet.engine.hearing.HearingInputs` ``h`` (its link budget, the
map's walls, the shadowing field; ``sa``, ``sb`` the field at the two ends; see :mod:`amronet.engine.hearing`)::

    @njit(cache=True)
    def cone_margin(xa, ya, xb, yb, d, sa, sb, floor_db, h):
        return 10.0 * (h.r_c - d) / h.r_c

    @MEDIA.register("cone")
    class Cone(RadioMedium):
        link_margin = cone_margin

That one kernel decides the neighbour table, coverage (``radio.model: cone`` in a scenario: runs, coverage,
agents' connection, the signal layer and ``amronet radio-map`` follow it) and the signal map. No link may be longer
than :attr:`RadioMedium.reach` (the table's search radius: ``r_c`` without shadowing; override it for a model that
reaches farther). A model may declare the fast paths it supports (class attributes):

* :attr:`~RadioMedium.margin_bound`: a compiled upper bound of its margin (see :mod:`amronet.engine.hearing`):
  coverage and the signal map skip blocks of cells that cannot be heard. Without one every cell within reach is
  tested, and the signal map tests the whole map (or give :meth:`~RadioMedium.signal_reach`).
* :attr:`~RadioMedium.every_pair_is_link`: every pair within reach is a link whose margin follows from its length
  by the link budget (the unit disk): the table needs no margin kernel, and every algorithm's compiled stretches
  may run (agent-assisted ones run under the built-in path-loss law too: :attr:`~RadioMedium.stretch_inputs`).
* :attr:`~RadioMedium.disk_coverage`: a cell is heard exactly when its centre is within ``r_c`` of a node (Eq. (1)
  of the paper): coverage in closed form, both methods, all runs of a batch in one call.

A model that lacks one of them takes the slower path, and the first time it does in a process it says so in the
log (logger ``amronet.engine.radio``, one debug message per model: a user who chose the model has nothing to fix).
"""

from __future__ import annotations

import logging
import math
from collections.abc import Callable
from typing import Any, ClassVar

import numpy as np

from amronet.engine.coverage import CoverageArea
from amronet.engine.coverage_heard import HeardCells
from amronet.engine.hearing import HearingInputs, path_loss_bound, path_loss_margin
from amronet.engine.links import NO_PREVIOUS, keep_entries, losses
from amronet.engine.margin_kernels import MarginKernels, margin_kernels
from amronet.engine.neighbours import GroupIds, neighbour_csr_checked
from amronet.engine.propagation import LinkBudget
from amronet.engine.radio_traits import DEFAULT_WALL_DB
from amronet.engine.shadowing import ShadowingField
from amronet.engine.table import NeighbourTable
from amronet.registry import Registry
from amronet.world.occupancy import OccupancyMap

__all__ = ["DEFAULT_WALL_DB", "MEDIA", "LogDistance", "MultiWall", "NeighbourTable", "RadioMedium", "UnitDisk",
           "make_medium"]

LOG = logging.getLogger(__name__)

_ANNOUNCED: set[tuple[type, tuple[str, ...]]] = set()
"""The models whose slower paths the log has been told of in this process, with those paths."""


class RadioMedium:
    """Base class of radio models: the link budget's law (:func:`~amronet.engine.hearing.path_loss_margin`).

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
        hearing: The inputs of the margin kernel.
    """

    name = "abstract"
    link_margin: ClassVar[Callable] = staticmethod(path_loss_margin)
    """The margin kernel (see the module doc); a class that gives its own and no bound has none."""
    margin_bound: ClassVar[Callable | None] = staticmethod(path_loss_bound)
    """A compiled upper bound of :attr:`link_margin` (fast path: blocks of cells skipped), or ``None``."""
    every_pair_is_link: ClassVar[bool] = False
    """Fast path: every pair within :attr:`reach` is a link, its margin that of its length (no margin kernel)."""
    disk_coverage: ClassVar[bool] = False
    """Fast path: a cell is heard exactly when its centre is within ``r_c`` of a node (Eq. (1))."""
    default_exponent: ClassVar[float] = 2.5
    """Path-loss exponent when the scenario gives none."""
    default_shadowing_db: ClassVar[float] = 0.0
    """Shadowing when the scenario gives none."""
    uses_walls: ClassVar[bool] = False
    uses_shadowing: ClassVar[bool] = False

    def __init_subclass__(cls, **kwargs: Any) -> None:
        super().__init_subclass__(**kwargs)
        own = vars(cls)
        if "link_margin" in own and "margin_bound" not in own:
            cls.margin_bound = None  # a bound belongs to its margin
        for name in ("link_margin", "margin_bound"):  # compiled functions bind like methods: store them static
            if own.get(name) is not None and not isinstance(own[name], staticmethod):
                setattr(cls, name, staticmethod(own[name]))

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
        self._previous: tuple | None = None
        """The last candidate table with margins ``(xy, indptr, indices, margin)``: links between nodes that have not
        moved since keep their margin (most of a deployed network stands still while agents and explorers move)."""
        self.hearing = HearingInputs.from_budget(budget, omap, self.shadowing, walls=self.uses_walls)
        self._plain = self.hearing.plain()
        self._kernels: MarginKernels | None = None
        self._told = False  # whether _announce ran
        self._heard: HeardCells | None = None

    @property
    def r_c(self) -> float:
        """The median range without walls and shadowing (the paper's communication radius)."""
        return self.budget.r_c

    @property
    def reach(self) -> float:
        """The radius within which links are searched: no link is longer."""
        return self.budget.reach if self.shadowing is not None else self.budget.r_c

    @property
    def kernels(self) -> MarginKernels:
        """The compiled kernels of this model's margin kernel."""
        if self._kernels is None:
            self._kernels = margin_kernels(type(self).link_margin, type(self).margin_bound)
        return self._kernels

    @property
    def keeps_every_pair(self) -> bool:
        """Whether a table is every pair the search finds within :attr:`reach`, as it is (the unit disk).

        So it is when the model declares :attr:`every_pair_is_link` and no link is lost (single runs, none failed).
        """
        return self.every_pair_is_link and not self.packet_loss

    @property
    def stretch_inputs(self) -> tuple | None:
        """What a compiled stretch that builds this medium's tables itself needs: its margin inputs, or ``None``.

        Under :attr:`keeps_every_pair` inputs without walls and shadowing (every pair within reach is a link); under
        the built-in path-loss law without packet loss :attr:`hearing` (a link: a pair whose margin is ``>= 0``).
        """
        if self.keeps_every_pair:
            return HearingInputs.from_budget(self.budget, None, None, walls=False).plain()
        return self._plain if type(self).link_margin is path_loss_margin and not self.packet_loss else None

    def signal_reach(self, floor_db: float) -> float:
        """The farthest a link with a margin of at least ``floor_db`` may reach (``inf``: unknown, the whole map).

        The link budget's law for its own margin kernel; a model with another gives its own or none.
        """
        if type(self).link_margin is not path_loss_margin:
            return math.inf
        h = self.hearing
        return h.r_c * 10.0 ** ((h.clip - floor_db) / h.n10)

    def update(self, xy: np.ndarray, groups: np.ndarray | None = None, silent: np.ndarray | None = None
               ) -> NeighbourTable:
        """Build this step's neighbour table from all robot positions ``(N, 2)`` (of several runs: ``groups``).

        ``silent``: mask of nodes that send nothing (failed nodes): they have no links, but stay in the geometric
        table (:attr:`NeighbourTable.geometric`) that body sensors and collisions read.
        """
        xy = np.array(xy, dtype=float)
        if xy.ndim != 2 or xy.shape[1] != 2:
            raise ValueError(f"xy must have shape (N, 2), got {xy.shape}")
        if not self.keeps_every_pair:
            self._announce()
        indptr, indices, dist = neighbour_csr_checked(xy, self.reach, self._group_ids(groups, len(xy)))
        return self._links(xy, groups, indptr, indices, dist, self._margins(xy, indptr, indices, dist), silent)

    def _links(self, xy: np.ndarray, groups: np.ndarray | None, indptr: np.ndarray, indices: np.ndarray,
               dist: np.ndarray, margin: np.ndarray | None, silent: np.ndarray | None) -> NeighbourTable:
        """:meth:`update`'s table of the pairs searched, of their margins (``None``: every pair is a link)."""
        b = self.budget
        keep = None if margin is None else margin >= 0.0
        if silent is not None and silent.any():
            rows = np.repeat(np.arange(len(xy)), np.diff(indptr))
            heard = ~(silent[rows] | silent[indices])
            keep = heard if keep is None else keep & heard
        if self.packet_loss:
            lost = losses(self._loss_rng, indptr, indices, b.margin_db(dist) if margin is None else margin)
            keep = ~lost if keep is None else keep & ~lost
        if keep is None or keep.all():  # (by position, in the fields' order: keywords cost more than the rest)
            return NeighbourTable(xy, self.reach, indptr, indices, dist, groups, b.threshold_dbm, margin, b.exponent)
        candidates = NeighbourTable(xy=xy, r=self.reach, indptr=indptr, indices=indices, dist=dist, groups=groups,
                                    threshold_dbm=b.threshold_dbm, exponent=b.exponent, link_margin=margin)
        full = b.margin_db(dist) if margin is None else margin
        indptr, indices, dist, kept = keep_entries(indptr, indices, dist, full, keep)
        return NeighbourTable(xy, self.reach, indptr, indices, dist, groups, b.threshold_dbm,
                              None if margin is None else kept, b.exponent, candidates)

    def _margins(self, xy: np.ndarray, indptr: np.ndarray, indices: np.ndarray, dist: np.ndarray
                 ) -> np.ndarray | None:
        """Margin of every candidate link (CSR order, symmetric); ``None``: every candidate is a link, by its length."""
        if self.every_pair_is_link:
            return None
        prev = self._previous if self._previous is not None else NO_PREVIOUS
        margin = self.kernels.candidate_margins(xy, indptr, indices, dist, *prev, self._plain)
        self._previous = (xy, indptr, indices, margin)
        return margin

    def plain_table(self, xy: np.ndarray, indptr: np.ndarray, indices: np.ndarray, dist: np.ndarray,
                    groups: np.ndarray | None = None, margin: np.ndarray | None = None,
                    silent: np.ndarray | None = None) -> NeighbourTable:
        """:meth:`update`'s table of a compiled search's pairs, with their ``margin`` (``None``: all are links)."""
        if margin is not None:
            self._previous = (xy, indptr, indices, margin)  # as _margins leaves it
        return self._links(xy, groups, indptr, indices, dist, margin, silent)

    def _group_ids(self, groups: np.ndarray | None, n: int) -> GroupIds:
        """``groups`` checked for ``n`` points; kept while the same array (a loop's, for all its steps) comes back."""
        known = self._groups
        if known is None or known.source is not groups or len(known.ids) != n:
            known = self._groups = GroupIds.of(groups, n)
        return known

    def _announce(self) -> None:
        """Say in the log, once per model in a process, which slower paths it takes (see the module doc)."""
        if self._told:
            return
        self._told = True
        slower = []
        if not self.keeps_every_pair:
            why = "packet loss drops links at random" if self.every_pair_is_link else "no every_pair_is_link"
            but = " but for agent-assisted runs" if self.stretch_inputs is not None else ""
            slower.append(f"no compiled stretches{but}, steps are taken one at a time ({why})")
        if not self.disk_coverage:
            slower.append("coverage is decided cell by cell, run by run (no disk_coverage)")
        if type(self).margin_bound is None:
            slower.append("coverage and the signal map test every cell within reach (no margin_bound)")
        key = (type(self), tuple(slower))
        if slower and key not in _ANNOUNCED:
            _ANNOUNCED.add(key)
            LOG.debug("radio model %s takes slower paths: %s", self.name, "; ".join(slower))

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
            ``(coverage, linked coverage)`` per run, the same numbers as :meth:`coverage`, in one compiled call under
            :attr:`disk_coverage` (the raster method); ``None`` otherwise (the caller then asks run by run).
        """
        if self.disk_coverage and method == "raster":
            return area.run_fractions(xy, network, linked, blocks, self.r_c)
        return None

    def coverage(self, area: CoverageArea, xy: np.ndarray, method: str = "raster") -> float:
        """Coverage under this radio: the fraction of ``area`` where a receiver would hear a node of ``xy``.

        Under :attr:`disk_coverage` this is Eq. (1) (:meth:`CoverageArea.fraction`, either method). Other models
        decide cell by cell at the cell centres (the raster method).

        Raises:
            ValueError: ``method`` is ``exact`` for a model without :attr:`disk_coverage`.
        """
        if self.disk_coverage:
            return area.fraction(xy, self.r_c, method=method)
        if method != "raster":
            raise ValueError(f"coverage method {method!r} is only defined for the unit disk; use raster")
        return np.float64(np.count_nonzero(self.covered_mask(area, xy))) / area.n_cells

    def covered_mask(self, area: CoverageArea, xy: np.ndarray) -> np.ndarray:
        """Boolean mask of the cells of ``area`` where a receiver would hear a node of ``xy``."""
        if self.disk_coverage:
            return area.covered_mask(xy, self.r_c)
        self._announce()
        return self.heard.covered(area, xy, self.reach)

    def signal_dbm(self, omap: OccupancyMap, xy: np.ndarray, floor_db: float = -30.0,
                   progress: Callable[[int, int], None] | None = None) -> np.ndarray:
        """Best RSSI (dBm) at every cell centre of ``omap`` over the nodes ``xy``; ``progress(done, total)`` nodes.

        NaN where every node is more than ``-floor_db`` dB below the usable threshold (or there are no nodes).
        """
        if type(self).margin_bound is None:
            self._announce()
        out = self.heard.best_margins(omap, xy, floor_db, self.signal_reach(floor_db), progress)
        out[~np.isfinite(out)] = np.nan
        return out + self.budget.threshold_dbm

    @property
    def heard(self) -> HeardCells:
        """Coverage and signal maps by the margin kernel (with its running union of the cells heard)."""
        if self._heard is None:
            self._heard = HeardCells(self.hearing, self.kernels)
        return self._heard


MEDIA: Registry[type[RadioMedium]] = Registry("radio model")
"""Radio models by name; a model registers itself with ``@MEDIA.register(name)``."""


@MEDIA.register("unit-disk")
class UnitDisk(RadioMedium):
    """Unit disk graph: two nodes are linked exactly when their distance is at most ``r_c`` (the paper's).

    Its signal map is the link budget's law without walls and shadowing.
    """

    every_pair_is_link = True
    disk_coverage = True


class _PathLoss(RadioMedium):
    """Models whose links are decided by their margin: distance, shadowing and, with walls, the walls crossed."""

    uses_shadowing = True

    def _margins(self, xy: np.ndarray, indptr: np.ndarray, indices: np.ndarray, dist: np.ndarray
                 ) -> np.ndarray | None:
        h = self.hearing
        if h.clip == 0.0 and h.wall_db == 0.0:
            return None  # no shadowing, no walls: the unit disk, decided by distance
        return super()._margins(xy, indptr, indices, dist)


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
    """The radio medium registered as ``model`` (``radio.model``), made as :class:`RadioMedium` takes its arguments.

    Raises:
        ScenarioError: ``model`` is unknown (field ``radio.model``).
    """
    return MEDIA.lookup(model, "radio.model")(budget, omap=omap, rng=rng, packet_loss=packet_loss)
