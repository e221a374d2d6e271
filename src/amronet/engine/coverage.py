"""Coverage, Eq. (1) of the paper: the area of the union of the nodes' disks over the area that counts.

``Coverage = |(D_1 u ... u D_N) n M| / |M|`` where ``D_i`` is the disk of radius ``r`` around node ``i`` and
``M`` is the area that counts (usually the reachable free space), given as a boolean mask of map cells.

Two methods, one class that prepares the mask once:

* ``"raster"`` (the default) counts the mask cells whose **centre** lies within ``r`` of some node, i.e. cell
  ``(i, j)`` with centre ``(cx, cy) = (ox + (j + 0.5) * res, oy + (i + 0.5) * res)`` is covered when
  ``(cx - x)**2 + (cy - y)**2 <= r**2`` (evaluated exactly this way in float64). In numba
  (:mod:`amronet.engine.coverage_kernels`): every disk's column interval in each row it spans, in closed form (the
  test above decides an end within rounding error of a cell centre), painted into a bitset of the rows and counted
  under the mask's bits.
* ``"exact"`` intersects the polygonal union of the disks with the polygon of the mask cells (shapely 2).
  Each disk is a regular ``4 * QUAD_SEGS``-gon with the **area-preserving** circumradius
  ``r' = r * sqrt(2 pi / (n sin(2 pi / n)))``, so a lone disk has exactly the area ``pi r**2``.

How far apart are the two? They differ only in mask cells that some disk's boundary crosses: such a cell
counts 0 or 1 in ``raster`` but its covered fraction in ``exact``. With ``rho = r / res`` the disk radius in
cells, ``N`` nodes and ``A`` mask cells:

* always: ``|raster - exact| <= B / A``, where ``B`` is the number of mask cells whose centre lies within
  ``res / sqrt(2) + 0.0009 r`` of some disk's boundary circle (the second term is the 64-gon's largest radial
  deviation from the circle), so ``B <~ 2 pi rho (sqrt(2) + 0.0018 rho) N``, about ``9 N rho``: relative to
  the disks' area the bound falls like ``1 / rho``;
* for layouts not aligned with the grid the per-cell errors cancel (the Gauss circle problem): measured
  ``|raster - exact| ~ 0.7 sqrt(N rho) / A`` rms, at most ``3.2 sqrt(N rho) / A`` in ~10^4 random layouts.
  On maps of 200 to 300 cells a side with up to 60 nodes and ``3 <= rho <= 40`` that is at most 0.08
  percentage points; 0.2 points need ``A >~ 1600 sqrt(N rho)`` cells (e.g. 60 nodes at ``rho = 40``: 280 x 280
  mask cells). On small maps the agreement in percentage points is worse whatever ``rho`` is.

Example:
    >>> import numpy as np
    >>> from amronet.world import OccupancyMap
    >>> omap = OccupancyMap("open", 0.02, (0.0, 0.0), np.zeros((300, 300), dtype=np.int8))
    >>> area = CoverageArea(omap, omap.free)
    >>> round(area.fraction(np.array([[3.0, 3.0]]), 1.0), 3)  # pi / 36
    0.087
"""

from __future__ import annotations

import math

import numpy as np
import shapely

from amronet.engine.coverage_kernels import mask_words, scan, scan_runs
from amronet.world.occupancy import OccupancyMap

__all__ = ["METHODS", "QUAD_SEGS", "CoverageArea", "disk_radius_area_preserving"]

METHODS: tuple[str, ...] = ("raster", "exact")
"""The coverage methods :meth:`CoverageArea.fraction` accepts."""

QUAD_SEGS: int = 16
"""Segments per quarter circle of the ``exact`` method's disks (a 64-gon)."""


def disk_radius_area_preserving(r: float, n: int) -> float:
    """Circumradius of the regular ``n``-gon whose area equals that of the disk of radius ``r``.

    Args:
        r: Disk radius.
        n: Number of vertices of the polygon (``n >= 3``).

    Returns:
        ``r * sqrt(2 pi / (n sin(2 pi / n)))``.
    """
    return r * math.sqrt(2.0 * math.pi / (n * math.sin(2.0 * math.pi / n)))


# --------------------------------------------------------------------------------------------------------
# the area that counts
# --------------------------------------------------------------------------------------------------------


def _row_runs(mask: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Horizontal runs of True cells: arrays ``(row, start, end)`` with ``end`` exclusive."""
    padded = np.zeros((mask.shape[0], mask.shape[1] + 2), dtype=np.int8)
    padded[:, 1:-1] = mask
    d = np.diff(padded, axis=1)
    r0, c0 = np.nonzero(d == 1)
    _, c1 = np.nonzero(d == -1)  # same row-major order, so starts and ends pair up
    return r0, c0, c1


class CoverageArea:
    """The area that counts, prepared once per map (and per mask) for fast repeated coverage queries.

    Args:
        omap: The map; only its shape, resolution and origin are used.
        mask: Boolean array of the map's shape: the cells that count (e.g. the reachable free space).

    Attributes:
        omap: The map.
        mask: The mask, a read-only boolean copy.
        n_cells: Number of cells in the mask.
        area_m2: Area of the mask in square metres, ``n_cells * resolution**2``.

    Raises:
        ValueError: If the mask's shape differs from the map's or the mask is empty.
    """

    def __init__(self, omap: OccupancyMap, mask: np.ndarray) -> None:
        mask = np.array(mask, dtype=bool)  # a copy: later changes by the caller must not leak in
        if mask.shape != omap.shape:
            raise ValueError(f"mask shape {mask.shape} differs from the map's shape {omap.shape}")
        self.n_cells = int(np.count_nonzero(mask))
        if self.n_cells == 0:
            raise ValueError("mask has no cells: the area that counts is empty")
        mask.flags.writeable = False
        self.omap = omap
        self.mask = mask
        self.area_m2 = self.n_cells * omap.resolution**2
        self._res = float(omap.resolution)
        self._ox = float(omap.origin[0])
        self._oy = float(omap.origin[1])
        self._words = mask_words(mask)
        self._ncols = int(mask.shape[1])
        self._no_paint = np.zeros((1, 1), dtype=bool)
        rows = np.flatnonzero(mask.any(axis=1))
        cols = np.flatnonzero(mask.any(axis=0))
        self._bounds = (  # of the mask cells, in metres
            self._ox + cols[0] * self._res,
            self._oy + rows[0] * self._res,
            self._ox + (cols[-1] + 1) * self._res,
            self._oy + (rows[-1] + 1) * self._res,
        )
        self._polygon: shapely.Geometry | None = None
        self._prepared = False

    @property
    def polygon(self) -> shapely.Geometry:
        """The mask as a shapely (Multi)Polygon: the union of its cells, built on first use and cached."""
        if self._polygon is None:
            rows, c0, c1 = _row_runs(self.mask)
            res, ox, oy = self._res, self._ox, self._oy
            boxes = shapely.box(ox + c0 * res, oy + rows * res, ox + c1 * res, oy + (rows + 1) * res)
            # union_all leaves a vertex at every row boundary of a straight wall; simplify(0) drops the
            # collinear ones (3x fewer vertices on real maps, faster intersections), the area is unchanged
            self._polygon = shapely.simplify(shapely.union_all(boxes), 0.0)
        return self._polygon

    def _check(self, xy: np.ndarray, r: float) -> np.ndarray:
        number = isinstance(r, int | float | np.floating | np.integer) and not isinstance(r, bool)
        if not (number and math.isfinite(r) and r > 0):
            raise ValueError(f"r must be a finite number > 0, got {r!r}")
        if not math.isfinite(float(r) * float(r)):  # the cell-centre test squares it
            raise ValueError(f"r must be at most 1e150 (its square a finite float), got {r!r}")
        xy = np.ascontiguousarray(xy, dtype=np.float64)
        if xy.ndim != 2 or xy.shape[1] != 2:
            raise ValueError(f"xy must have shape (N, 2), got {xy.shape}")
        return xy

    def _raster(self, xy: np.ndarray, r: float, out: np.ndarray, paint: bool) -> int:
        count = scan(xy, float(r), self._ox, self._oy, self._res, self._words, self._ncols, out, paint)
        if count < 0:
            raise ValueError("xy must be finite")
        return count

    def fraction(self, xy: np.ndarray, r: float, method: str = "raster") -> float:
        """Coverage, Eq. (1): the fraction of the area that counts within ``r`` of some node.

        Args:
            xy: Node positions in world coordinates, shape ``(N, 2)``; nodes outside the map still cover
                what their disks reach inside it.
            r: Disk (communication) radius in metres.
            method: ``"raster"`` (mask cells whose centre is within ``r``; fast) or ``"exact"`` (polygon
                areas).

        Returns:
            Coverage in ``[0, 1]``; ``0.0`` for no nodes.

        Raises:
            ValueError: If ``r`` is not finite and positive, ``method`` is unknown, or ``xy`` is not a finite
                ``(N, 2)`` array.
        """
        xy = self._check(xy, r)
        if method == "raster":
            if xy.shape[0] == 0:
                return 0.0
            return self._raster(xy, r, self._no_paint, False) / self.n_cells
        if method == "exact":
            if not np.isfinite(xy).all():
                raise ValueError("xy must be finite")
            if xy.shape[0] == 0:
                return 0.0
            return min(self._exact_area(xy, float(r)) / self.area_m2, 1.0)
        raise ValueError(f"method must be one of {METHODS}, got {method!r}")

    def _exact_area(self, xy: np.ndarray, r: float) -> float:
        rp = disk_radius_area_preserving(r, 4 * QUAD_SEGS)
        x, y = xy[:, 0], xy[:, 1]
        xmin, ymin, xmax, ymax = self._bounds
        near = (x > xmin - rp) & (x < xmax + rp) & (y > ymin - rp) & (y < ymax + rp)
        if not near.any():  # no disk reaches the mask's bounding box
            return 0.0
        union = shapely.union_all(shapely.buffer(shapely.points(xy[near]), rp, quad_segs=QUAD_SEGS))
        poly = self.polygon
        if not self._prepared:
            shapely.prepare(poly)
            self._prepared = True
        if shapely.contains_properly(poly, union):
            return float(union.area)
        xmin, ymin, xmax, ymax = union.bounds
        clipped = shapely.clip_by_rect(poly, xmin, ymin, xmax, ymax)
        return float(shapely.intersection(union, clipped).area)

    def run_fractions(self, xy: np.ndarray, network: np.ndarray, linked: np.ndarray, blocks: np.ndarray, r: float
                      ) -> list[tuple[float, float]]:
        """Raster coverage of several runs' nodes in one compiled call.

        Per run, :meth:`fraction` of its ``network`` nodes and of its ``linked`` ones: a batch's record, without a
        Python call per run.

        Args:
            xy: The positions of every run's robots ``(N, 2)``, a run's in a block of rows.
            network: Mask ``(N,)`` of the nodes that cover.
            linked: Mask ``(N,)`` of the covering nodes linked to a base station.
            blocks: ``(runs, 2)`` first and past-the-last row of each run.
            r: Disk radius in metres.

        Returns:
            Per run, ``(coverage, linked coverage)``, each what :meth:`fraction` gives for those nodes.

        Raises:
            ValueError: As :meth:`fraction`.
        """
        xy = self._check(xy, r)
        counts = np.zeros((len(blocks), 2), dtype=np.int64)
        starts, stops = (np.ascontiguousarray(blocks[:, j], dtype=np.int64) for j in (0, 1))  # one kernel version
        ok = scan_runs(xy, np.ascontiguousarray(network, dtype=np.bool_), np.ascontiguousarray(linked, dtype=np.bool_),
                       starts, stops, float(r), self._ox, self._oy, self._res, self._words, self._ncols, counts)
        if not ok:
            raise ValueError("xy must be finite")
        n = self.n_cells
        return [(int(a) / n, int(b) / n) for a, b in counts.tolist()]

    def covered_mask(self, xy: np.ndarray, r: float) -> np.ndarray:
        """Boolean ``(rows, cols)`` array of the mask cells whose centre lies within ``r`` of some node.

        Args:
            xy: Node positions in world coordinates, shape ``(N, 2)``.
            r: Disk radius in metres.

        Returns:
            The covered mask cells (the raster method's picture: its count divided by ``n_cells`` is the
            raster coverage).

        Raises:
            ValueError: If ``r`` is not finite and positive or ``xy`` is not a finite ``(N, 2)`` array.
        """
        xy = self._check(xy, r)
        out = np.zeros(self.mask.shape, dtype=bool)
        if xy.shape[0]:
            self._raster(xy, r, out, True)
            out &= self.mask
        return out
