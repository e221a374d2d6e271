"""Static regular placement patterns for communication coverage with connectivity at ``r = r_c`` (paper 2.3, 5.1.1).

Four patterns, every link exactly ``r`` long (so each is connected in the unit-disk model):

* ``"r-strip"`` (Bai et al., MobiHoc 2006): rows ``h = (1 + sqrt(3)/2) r`` apart, nodes ``r`` apart in a row,
  odd rows shifted by ``r/2``; the rows alone cover the plane. Rows are farther apart than ``r``, so each pair
  of adjacent rows gets one *connector* at the midpoint of a row-``k`` node and its nearest row-``k+1`` node
  (``0.966 r`` from both; see ``reference/baselines.md``: the paper's printed connector coordinates are
  garbled). Density ``0.536 / r**2``.
* ``"hexagonal"``: honeycomb of edge ``r``, ``0.77 / r**2``. ``"square"``: spacing ``r``, ``1 / r**2``.
  ``"triangular"``: spacing ``r``, ``1.155 / r**2``.

:func:`estimate` is the paper's estimated count ``ceil(density * area / r**2)``; :func:`place` finds the
actual placement in a bounded area: the lattice, shifted by an offset (and optionally turned by 90 degrees),
restricted to nodes inside the area (closed rectangle, or nodes lying in a counted cell of a mask). Offsets
are searched on a grid over the lattice's fundamental cell (``steps`` divisions per side) plus the *snap*
offsets that put a node exactly on an edge of the area's bounding box (where the node count changes). The
result is the connected placement with the fewest nodes among those whose raster coverage is within ``tol``
of the highest; candidates are evaluated in order of node count, and the search stops early once one reaches
coverage ``1 - tol`` connected (no candidate with more nodes can then win).

Why a tolerance (``DEFAULT_TOL = 1e-4``, 0.01 % of the area, ~6 cells of the 256 x 256 search raster of
32 m x 32 m): near the tight coverings (r-strip, honeycomb) holes shrink continuously to nothing as the
offset approaches a snap value, so "highest coverage" below the raster's resolution is noise. With it, 32 m x
32 m at ``r = 4`` gives the paper's 44 (r-strip) and 55 (hexagonal), both leaving holes of < 0.1 m² at the
edges as the paper's Fig. 6 does; ``tol=0`` asks for the raster's full coverage: 46 and 60. The square and
triangular grids overlap so much that boundary nodes cover beyond the area: they often need *fewer* nodes
than the density estimate (64 and 72 against 64 and 74 here).

Links are tested at ``r * (1 + LINK_SLACK)``: lattice neighbours are exactly ``r`` apart, which floating-point
coordinates would otherwise break at random.

Example:
    >>> estimate("r-strip", 32 * 32, 4.0), estimate("hexagonal", 32 * 32, 4.0)
    (35, 50)
    >>> p = place("r-strip", (32.0, 32.0), 4.0)
    >>> p.count, p.connected, int(p.connector.sum()), round(p.coverage, 3)
    (44, True, 4, 1.0)
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from fractions import Fraction
from typing import Any

import numpy as np
from scipy.sparse import csr_matrix
from scipy.sparse.csgraph import connected_components

from amronet.coverage import CoverageArea
from amronet.neighbours import neighbour_csr, pairs_from_csr
from amronet.world.occupancy import FREE, OccupancyMap

__all__ = [
    "DEFAULT_STEPS",
    "DEFAULT_TOL",
    "DENSITY",
    "LINK_SLACK",
    "PATTERNS",
    "PatternArea",
    "Placement",
    "as_area",
    "estimate",
    "is_connected",
    "lattice",
    "pattern_links",
    "place",
    "place_all",
]

PATTERNS: tuple[str, ...] = ("r-strip", "hexagonal", "square", "triangular")
"""The pattern names, in the paper's order (sparsest first)."""

DENSITY: dict[str, float] = {"r-strip": 0.536, "hexagonal": 0.77, "square": 1.0, "triangular": 1.155}
"""Nodes per ``r**2`` of each infinite pattern (paper section 2.3)."""

DEFAULT_STEPS: int = 16
"""Default offset grid: divisions of each side of the lattice's fundamental cell."""

DEFAULT_TOL: float = 1e-4
"""Default coverage tolerance: raster coverages within this of the best count as best (raster noise)."""

LINK_SLACK: float = 1e-9
"""Relative slack of the link test, so that lattice neighbours exactly ``r`` apart stay linked."""

_S3 = math.sqrt(3.0)
_MAX_CANDIDATE_POINTS = 4_000_000  # candidates x lattice points held at once in the offset search
_EXACT_TIES = 8  # exact coverage decides between at most this many raster ties


@dataclass(frozen=True)
class _Lattice:
    """Lattice ``basis + i * (px, 0) + j * (sx, py)`` in the pattern frame."""

    px: float
    sx: float
    py: float
    basis: tuple[tuple[float, float], ...]


def _lattice(pattern: str, r: float) -> _Lattice:
    if pattern == "r-strip":
        return _Lattice(r, r / 2, (1 + _S3 / 2) * r, ((0.0, 0.0),))
    if pattern == "hexagonal":  # honeycomb: two nodes per cell, a vertical edge (0, 0)-(0, r)
        return _Lattice(_S3 * r, _S3 / 2 * r, 1.5 * r, ((0.0, 0.0), (0.0, r)))
    if pattern == "square":
        return _Lattice(r, 0.0, r, ((0.0, 0.0),))
    return _Lattice(r, r / 2, _S3 / 2 * r, ((0.0, 0.0),))


def _check(pattern: str, r: float) -> float:
    if pattern not in PATTERNS:
        raise ValueError(f"pattern must be one of {PATTERNS}, got {pattern!r}")
    if (
        isinstance(r, bool)
        or not isinstance(r, int | float | np.integer | np.floating)
        or not (math.isfinite(r) and r > 0)
    ):
        raise ValueError(f"r must be a finite number > 0, got {r!r}")
    return float(r)


def estimate(pattern: str, area_m2: float, r: float) -> int:
    """The paper's estimated node count ``ceil(DENSITY[pattern] * area_m2 / r**2)``.

    Args:
        pattern: One of :data:`PATTERNS`.
        area_m2: Area in square metres (``>= 0``).
        r: Communication radius in metres.

    Returns:
        The estimate (e.g. 35 for the r-strip and 50 for the hexagonal grid in 32 m x 32 m at ``r = 4``).

    Raises:
        ValueError: Unknown pattern, or ``r`` or ``area_m2`` not finite and in range.
    """
    r = _check(pattern, r)
    if not (math.isfinite(area_m2) and area_m2 >= 0):
        raise ValueError(f"area_m2 must be a finite number >= 0, got {area_m2!r}")
    return math.ceil(DENSITY[pattern] * area_m2 / r**2 - 1e-9)


# --------------------------------------------------------------------------------------------------------
# the area
# --------------------------------------------------------------------------------------------------------


@dataclass(frozen=True, eq=False)
class PatternArea:
    """An area prepared for placing patterns: a closed rectangle ``[0, w] x [0, h]`` or the cells of a mask.

    Attributes:
        omap: The map. For a rectangle: an all-free map of it at the search raster's resolution.
        mask: Boolean ``omap.shape``: the cells that count.
        rectangle: ``(w, h)`` for a rectangle, else None.
        area_m2: Size of the area that counts.
        bounds: ``(xmin, ymin, xmax, ymax)`` of the area in metres.
        coverage: Coverage of the area: raster for the offset search, exact for the reported number.
    """

    omap: OccupancyMap
    mask: np.ndarray
    rectangle: tuple[float, float] | None
    area_m2: float
    bounds: tuple[float, float, float, float]
    coverage: CoverageArea = field(repr=False)

    def inside(self, xy: np.ndarray) -> np.ndarray:
        """Boolean ``xy.shape[:-1]``: which points may hold a node (in the closed rectangle / a counted cell)."""
        xy = np.asarray(xy, dtype=float)
        if self.rectangle is not None:
            w, h = self.rectangle
            eps = 1e-9 * max(w, h)
            x, y = xy[..., 0], xy[..., 1]
            return (x >= -eps) & (x <= w + eps) & (y >= -eps) & (y <= h + eps)
        rows, cols = self.omap.world_to_cell(xy)
        nr, nc = self.mask.shape
        ok = (rows >= 0) & (rows < nr) & (cols >= 0) & (cols < nc)
        out = np.zeros(ok.shape, dtype=bool)
        out[ok] = self.mask[rows[ok], cols[ok]]
        return out


def _common_cell(w: float, h: float) -> float:
    """The largest length dividing both sides, which must be at least ``max(w, h) / 2048``."""
    fw, fh = Fraction(w).limit_denominator(2048), Fraction(h).limit_denominator(2048)
    den = math.lcm(fw.denominator, fh.denominator)
    g = float(Fraction(math.gcd(int(fw * den), int(fh * den)), den))
    if abs(float(fw) - w) > 1e-9 * w or abs(float(fh) - h) > 1e-9 * h or max(w, h) / g > 2048:
        raise ValueError(f"rectangle sides {w:g} x {h:g} m need a common divisor of at least 1/2048 of the longer side")
    return g


def as_area(
    area: tuple[float, float] | OccupancyMap | tuple[OccupancyMap, np.ndarray] | PatternArea,
    *,
    mask: np.ndarray | None = None,
    r: float | None = None,
) -> PatternArea:
    """Prepare an area for :func:`place` (reuse the result to place several patterns).

    Args:
        area: ``(width, height)`` in metres (the closed rectangle with its lower-left corner at the origin), an
            ``OccupancyMap`` (with ``mask``, or else its free cells count), ``(omap, mask)``, or a prepared area
            (returned as is).
        mask: Boolean ``omap.shape``: the cells that count, e.g. ``reachable_free(omap, base)``.
        r: The radius the area will be used with; a rectangle's search raster is ``min(r / 8, side / 256)``
            (and at least ``side / 1024``), rounded down to divide both sides.

    Returns:
        The prepared area.

    Raises:
        ValueError: Sides not positive or without a common divisor of at least 1/2048 of the longer side,
            or an empty or misshapen mask.
    """
    if isinstance(area, PatternArea):
        return area
    if isinstance(area, tuple) and len(area) == 2 and isinstance(area[0], OccupancyMap):
        area, mask = area
    if isinstance(area, OccupancyMap):
        mask = area.free if mask is None else np.asarray(mask)
        if mask.shape != area.shape or mask.dtype != np.bool_:
            raise ValueError(f"mask must be a boolean array of the map's shape {area.shape}")
        cov = CoverageArea(area, mask)  # raises on an empty mask
        rows, cols = np.flatnonzero(mask.any(axis=1)), np.flatnonzero(mask.any(axis=0))
        (x0, y0), (x1, y1) = area.cell_centres(np.array([rows[0], rows[-1]]), np.array([cols[0], cols[-1]]))
        half = area.resolution / 2
        return PatternArea(area, cov.mask, None, cov.area_m2, (x0 - half, y0 - half, x1 + half, y1 + half), cov)
    w, h = (float(v) for v in area)  # type: ignore[union-attr]
    if not (math.isfinite(w) and math.isfinite(h) and w > 0 and h > 0):
        raise ValueError(f"rectangle sides must be finite and > 0, got {w!r} x {h!r}")
    g = _common_cell(w, h)
    side = max(w, h)
    target = max(min((r if r else side) / 8, side / 256), side / 1024)
    res = g / math.ceil(g / target - 1e-9)
    cells = np.full((round(h / res), round(w / res)), FREE, dtype=np.int8)  # tiles the rectangle exactly
    omap = OccupancyMap(f"rectangle {w:g} m x {h:g} m", res, (0.0, 0.0), cells)
    cov = CoverageArea(omap, np.ones(omap.shape, dtype=bool))
    return PatternArea(omap, cov.mask, (w, h), w * h, (0.0, 0.0, w, h), cov)


# --------------------------------------------------------------------------------------------------------
# lattices in the pattern frame; the world frame is the pattern frame, or it turned by +90 degrees
# --------------------------------------------------------------------------------------------------------


def _to_world(p: np.ndarray, rotated: bool) -> np.ndarray:
    return np.stack([-p[..., 1], p[..., 0]], axis=-1) if rotated else p


def _pattern_bbox(bounds: tuple[float, float, float, float], rotated: bool) -> tuple[float, float, float, float]:
    x0, y0, x1, y1 = bounds
    return (y0, -x1, y1, -x0) if rotated else bounds


def _points(lat: _Lattice, bbox: tuple[float, float, float, float]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Lattice points (offset 0) that any offset in the fundamental cell can move into ``bbox``.

    Returns:
        ``(p, u, j)``: points ``(M, 2)``, half-step column ``u = 2 i + j`` and row ``j`` (used by the r-strip).
    """
    x0, y0, x1, y1 = bbox
    x0, y0 = x0 - lat.px, y0 - lat.py
    ps, us, js = [], [], []
    for bx, by in lat.basis:
        j = np.arange(math.floor((y0 - by) / lat.py), math.ceil((y1 - by) / lat.py) + 1)
        imin = np.floor((x0 - bx - j * lat.sx) / lat.px).astype(np.int64)
        imax = np.ceil((x1 - bx - j * lat.sx) / lat.px).astype(np.int64)
        i = imin[:, None] + np.arange(int((imax - imin).max()) + 1)[None, :]
        jj = np.broadcast_to(j[:, None], i.shape)
        keep = i <= imax[:, None]
        i, jj = i[keep], jj[keep]
        ps.append(np.stack([bx + i * lat.px + jj * lat.sx, by + jj * lat.py], axis=1))
        us.append(2 * i + jj)
        js.append(jj)
    return np.concatenate(ps), np.concatenate(us), np.concatenate(js)


def _strip_connectors(
    p: np.ndarray, u: np.ndarray, j: np.ndarray, ok: Callable[[np.ndarray], np.ndarray]
) -> np.ndarray:
    """Connectors of r-strip rows (pattern frame): a spanning forest of row runs, leftmost candidates first.

    Args:
        p: Row nodes ``(n, 2)``.
        u: Their half-step columns.
        j: Their rows.
        ok: Whether pattern-frame points may hold a node.

    Returns:
        Connector positions ``(m, 2)``; on a rectangle exactly one per pair of adjacent non-empty rows.
    """
    n = len(p)
    index = {(int(a), int(b)): k for k, (a, b) in enumerate(zip(u, j, strict=True))}
    parent = list(range(n))

    def find(a: int) -> int:
        while parent[a] != a:
            parent[a] = parent[parent[a]]
            a = parent[a]
        return a

    for (a, b), k in index.items():
        q = index.get((a + 2, b))
        if q is not None:
            parent[find(q)] = find(k)
    cand = sorted(
        (b, 2 * a + du, k, q)
        for (a, b), k in index.items()
        for du in (-1, 1)
        if (q := index.get((a + du, b + 1))) is not None
    )
    if not cand:
        return np.empty((0, 2))
    ks = np.array([c[2] for c in cand])
    qs = np.array([c[3] for c in cand])
    mids = (p[ks] + p[qs]) / 2
    good = ok(mids)
    out = []
    for m, k, q in zip(range(len(cand)), ks, qs, strict=True):
        if good[m]:
            a, b = find(int(k)), find(int(q))
            if a != b:
                parent[b] = a
                out.append(m)
    return mids[out]


def _nodes(
    pattern: str, r: float, p: np.ndarray, u: np.ndarray, j: np.ndarray, rotated: bool, inside: Callable
) -> tuple[np.ndarray, np.ndarray]:
    """World positions of the selected pattern-frame nodes plus, for the r-strip, its connectors."""
    xy = _to_world(p, rotated)
    conn = np.zeros(len(xy), dtype=bool)
    if pattern == "r-strip" and len(p):
        c = _strip_connectors(p, u, j, lambda q: inside(_to_world(q, rotated)))
        xy = np.concatenate([xy, _to_world(c, rotated)])
        conn = np.concatenate([conn, np.ones(len(c), dtype=bool)])
    return xy, conn


def lattice(
    pattern: str, r: float, width: float, height: float, offset: tuple[float, float] = (0.0, 0.0), rotated: bool = False
) -> tuple[np.ndarray, np.ndarray]:
    """All nodes of a pattern in the closed rectangle ``[0, width] x [0, height]``, without any search.

    Args:
        pattern: One of :data:`PATTERNS`.
        r: Communication radius (lattice spacing) in metres.
        width: Rectangle width in metres.
        height: Rectangle height in metres.
        offset: World position of the lattice node ``i = j = 0`` (as :attr:`Placement.offset`).
        rotated: Turn the pattern by 90 degrees (counter-clockwise).

    Returns:
        ``(xy, connector)``: positions ``(N, 2)`` and a boolean mask of the r-strip's connectors.
    """
    r = _check(pattern, r)
    bounds = (0.0, 0.0, float(width), float(height))
    eps = 1e-9 * max(width, height)

    def inside(q: np.ndarray) -> np.ndarray:
        return (q[..., 0] >= -eps) & (q[..., 0] <= width + eps) & (q[..., 1] >= -eps) & (q[..., 1] <= height + eps)

    lat = _lattice(pattern, r)
    ox, oy = (offset[1], -offset[0]) if rotated else offset
    k = math.floor(oy / lat.py)  # reduce the offset into the fundamental cell
    ox, oy = (ox - k * lat.sx) % lat.px, oy - k * lat.py
    p, u, j = _points(lat, _pattern_bbox(bounds, rotated))
    p = p + np.array([ox, oy])
    sel = inside(_to_world(p, rotated))
    return _nodes(pattern, r, p[sel], u[sel], j[sel], rotated, inside)


# --------------------------------------------------------------------------------------------------------
# connectivity
# --------------------------------------------------------------------------------------------------------


def pattern_links(xy: np.ndarray, r: float) -> np.ndarray:
    """Links ``(M, 2)`` (pairs ``i < j``) of the unit-disk graph at ``r * (1 + LINK_SLACK)``."""
    xy = np.asarray(xy, dtype=float).reshape(-1, 2)
    indptr, indices, _ = neighbour_csr(xy, r * (1 + LINK_SLACK))
    return pairs_from_csr(indptr, indices)


def is_connected(xy: np.ndarray, r: float) -> bool:
    """Whether the unit-disk graph at ``r * (1 + LINK_SLACK)`` has one component (True for 0 or 1 node)."""
    xy = np.asarray(xy, dtype=float).reshape(-1, 2)
    n = len(xy)
    if n <= 1:
        return True
    indptr, indices, _ = neighbour_csr(xy, r * (1 + LINK_SLACK))
    graph = csr_matrix((np.ones(len(indices), dtype=np.int8), indices, indptr), shape=(n, n))
    return connected_components(graph, directed=False, return_labels=False) == 1


# --------------------------------------------------------------------------------------------------------
# the offset search
# --------------------------------------------------------------------------------------------------------


@dataclass(frozen=True, eq=False)
class Placement:
    """A pattern placed in a bounded area.

    Attributes:
        pattern: The pattern's name.
        xy: Node positions ``(N, 2)`` in world metres (r-strip connectors last).
        count: ``N``.
        coverage: Exact coverage (Eq. (1)) of the area by disks of radius ``r``.
        connected: Whether the unit-disk graph at ``r`` is one component.
        offset: World position of the lattice's node ``i = j = 0`` (which may lie outside the area).
        rotated: Whether the pattern is turned by 90 degrees.
        r: The radius.
        estimate: The paper's estimate for the area (:func:`estimate`).
        connector: Boolean ``(N,)``: the r-strip's connector nodes.
        raster_coverage: The raster coverage the search ranked by.
    """

    pattern: str
    xy: np.ndarray
    count: int
    coverage: float
    connected: bool
    offset: tuple[float, float]
    rotated: bool
    r: float
    estimate: int
    connector: np.ndarray = field(repr=False)
    raster_coverage: float = field(repr=False)

    def to_dict(self) -> dict[str, Any]:
        """JSON-friendly summary (positions as a list of ``[x, y]``)."""
        return {
            "pattern": self.pattern, "density": DENSITY[self.pattern], "r": self.r, "estimated": self.estimate,
            "placed": self.count, "coverage": self.coverage, "connected": self.connected,
            "offset": list(self.offset), "rotated": self.rotated, "xy": self.xy.round(6).tolist(),
            "connector": self.connector.tolist(),
        }  # fmt: skip


def _offsets(lat: _Lattice, bbox: tuple[float, float, float, float], steps: int) -> np.ndarray:
    """Candidate offsets: a grid over the fundamental cell plus the offsets putting a node on a bbox edge."""
    x0, y0, x1, y1 = bbox
    xs = [k * lat.px / steps for k in range(steps)]
    ys = [k * lat.py / steps for k in range(steps)]
    for bx, by in lat.basis:
        xs += [(e - bx - jj * lat.sx) % lat.px for e in (x0, x1) for jj in (0, 1)]
        ys += [(e - by) % lat.py for e in (y0, y1)]
    xs_u = np.unique(np.round(np.array(xs) % lat.px, 12) % lat.px)
    ys_u = np.unique(np.round(np.array(ys) % lat.py, 12) % lat.py)
    return np.stack(np.meshgrid(xs_u, ys_u, indexing="ij"), axis=-1).reshape(-1, 2)


@dataclass
class _Candidate:
    rotated: bool
    offset: np.ndarray
    lower: int  # lower bound of the node count
    xy: np.ndarray | None = None
    connector: np.ndarray | None = None
    cov: float = -1.0
    _connected: bool | None = None

    def connected(self, r: float) -> bool:
        if self._connected is None:
            self._connected = is_connected(self.xy, r)
        return self._connected


def place(
    pattern: str,
    area: tuple[float, float] | OccupancyMap | tuple[OccupancyMap, np.ndarray] | PatternArea,
    r: float,
    *,
    mask: np.ndarray | None = None,
    steps: int = DEFAULT_STEPS,
    rotations: bool = True,
    tol: float = DEFAULT_TOL,
) -> Placement:
    """Place a pattern in a bounded area: fewest nodes among the connected placements of highest coverage.

    Args:
        pattern: One of :data:`PATTERNS`.
        area: ``(width, height)``, an ``OccupancyMap`` (with ``mask``), ``(omap, mask)`` or a :class:`PatternArea`.
        r: Communication radius ``r_c`` in metres (the lattice spacing).
        mask: The cells that count when ``area`` is a map (default: its free cells).
        steps: Offset grid: divisions per side of the fundamental cell (snap offsets are always added).
        rotations: Also try the pattern turned by 90 degrees.
        tol: Raster coverages within ``tol`` of the best connected one count as best.

    Returns:
        The placement; if no candidate is connected (possible on masks with obstacles) the best one, reported
        with ``connected=False``. An area too small to hold a node gives an empty placement.

    Raises:
        ValueError: Unknown pattern, ``r`` not finite and positive, ``steps < 1``, ``tol`` outside ``[0, 1)``,
            or a bad area (see :func:`as_area`).
    """
    r = _check(pattern, r)
    if not (isinstance(steps, int | np.integer) and steps >= 1):
        raise ValueError(f"steps must be an integer >= 1, got {steps!r}")
    if not (0 <= tol < 1):
        raise ValueError(f"tol must be in [0, 1), got {tol!r}")
    pa = as_area(area, mask=mask, r=r)
    lat = _lattice(pattern, r)
    bounds = pa.bounds
    if pa.rectangle is None:  # nodes exactly on the far edge of the mask lie in no cell: snap just inside
        eps = 1e-6 * pa.omap.resolution
        bounds = (bounds[0] + eps, bounds[1] + eps, bounds[2] - eps, bounds[3] - eps)
    cands: list[_Candidate] = []
    sel_of: dict[int, np.ndarray] = {}
    frames = {}
    for rotated in (False, True) if rotations else (False,):
        bbox = _pattern_bbox(bounds, rotated)
        p, u, j = _points(lat, bbox)
        offs = _offsets(lat, bbox, int(steps))
        frames[rotated] = (p, u, j)
        chunk = max(1, _MAX_CANDIDATE_POINTS // max(len(p), 1))
        for s in range(0, len(offs), chunk):
            o = offs[s : s + chunk]
            inside = pa.inside(_to_world(p[None, :, :] + o[:, None, :], rotated))
            lower = inside.sum(axis=1)
            if pattern == "r-strip" and pa.rectangle is not None:  # one connector per gap of non-empty rows
                rows = np.zeros((len(o), int(j.max() - j.min()) + 1), dtype=bool)
                ci, pi = np.nonzero(inside)
                rows[ci, j[pi] - j.min()] = True
                lower = lower + np.maximum(rows.sum(axis=1) - 1, 0)
            for k in range(len(o)):
                sel_of[len(cands)] = inside[k]
                cands.append(_Candidate(rotated, o[k], int(lower[k])))

    def evaluate(k: int) -> _Candidate:
        c = cands[k]
        p, u, j = frames[c.rotated]
        sel = sel_of[k]
        c.xy, c.connector = _nodes(pattern, r, p[sel] + c.offset, u[sel], j[sel], c.rotated, pa.inside)
        c.cov = pa.coverage.fraction(c.xy, r) if len(c.xy) else 0.0
        return c

    evaluated: list[int] = []
    stop = math.inf
    for k in sorted(range(len(cands)), key=lambda k: (cands[k].lower, k)):
        if cands[k].lower > stop:
            break
        c = evaluate(k)
        evaluated.append(k)
        if c.cov >= 1 - tol and len(c.xy) < stop and c.connected(r):
            stop = len(c.xy)
    best, exact = _select([cands[k] for k in evaluated], r, tol, pa)
    xy = best.xy if best.xy is not None else np.empty((0, 2))
    connector = best.connector if best.connector is not None else np.zeros(0, dtype=bool)
    ox, oy = _to_world(best.offset, best.rotated)
    return Placement(
        pattern=pattern, xy=xy, count=len(xy), coverage=exact, connected=best.connected(r),
        offset=(float(ox), float(oy)), rotated=best.rotated, r=r, estimate=estimate(pattern, pa.area_m2, r),
        connector=connector, raster_coverage=best.cov,
    )  # fmt: skip


def _select(evaluated: list[_Candidate], r: float, tol: float, pa: PatternArea) -> tuple[_Candidate, float]:
    """Fewest nodes (then highest coverage) among those within ``tol`` of the best connected coverage.

    Exact ties (same count and raster coverage: the raster cannot tell them apart) are decided by exact
    coverage among the (at most 8) whose nodes are most centred in the area's bounding box.

    Returns:
        The winner and its exact coverage.
    """
    by_cov = sorted(evaluated, key=lambda c: -c.cov)  # stable: ties keep the search order
    top = next((c.cov for c in by_cov if c.connected(r)), None)
    ref = by_cov[0].cov if top is None else top
    pool = sorted((c for c in evaluated if c.cov >= ref - tol), key=lambda c: (len(c.xy), -c.cov))
    first = pool[0] if top is None else next(c for c in pool if c.connected(r))
    if len(first.xy) == 0:
        return first, 0.0
    same = (c for c in pool if len(c.xy) == len(first.xy) and c.cov == first.cov)
    ties = [c for c in same if top is None or c.connected(r)]
    x0, y0, x1, y1 = pa.bounds

    def off_centre(c: _Candidate) -> float:
        lo, hi = c.xy.min(axis=0), c.xy.max(axis=0)
        return abs((lo[0] - x0) - (x1 - hi[0])) + abs((lo[1] - y0) - (y1 - hi[1]))

    ties = sorted(ties, key=off_centre)[:_EXACT_TIES]
    exact = [pa.coverage.fraction(c.xy, r, "exact") for c in ties]
    k = int(np.argmax(exact))
    return ties[k], exact[k]


def place_all(
    area: tuple[float, float] | OccupancyMap | tuple[OccupancyMap, np.ndarray] | PatternArea,
    r: float,
    patterns: Sequence[str] = PATTERNS,
    **kwargs: Any,
) -> dict[str, Placement]:
    """Place several patterns in one area (prepared once); keyword arguments go to :func:`place`.

    Returns:
        Pattern name to placement, in the order of ``patterns``.
    """
    mask = kwargs.pop("mask", None)
    pa = as_area(area, mask=mask, r=_check(patterns[0] if patterns else PATTERNS[0], r))
    return {name: place(name, pa, r, **kwargs) for name in patterns}
