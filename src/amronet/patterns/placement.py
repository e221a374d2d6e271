"""Placing a pattern in a bounded area: the offset search and its result, :class:`Placement`.

See :mod:`amronet.patterns` for the search (candidate offsets, the coverage tolerance, the early stop).

Before the lattice is generated, :func:`check_budget` estimates its points (the area's bounding box over the
lattice's cell) and the search's candidate offsets, and refuses (the resource guard, :mod:`amronet.limits`) a
placement that would not fit in the memory available, or one of more than ``limits.MAX_PATTERN_WORK`` lattice
points times candidates unless acknowledged (``force=True``, ``amronet patterns --force``).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from amronet import limits
from amronet.errors import AmronetError
from amronet.patterns.area import AreaLike, PatternArea, as_area
from amronet.patterns.lattices import (
    DENSITY,
    PATTERNS,
    Lattice,
    check_pattern,
    estimate,
    lattice_basis,
    lattice_nodes,
    lattice_points,
    pattern_bbox,
    to_world,
)
from amronet.patterns.links import is_connected

__all__ = ["DEFAULT_STEPS", "DEFAULT_TOL", "Placement", "check_budget", "place", "place_all"]

DEFAULT_STEPS: int = 16
"""Default offset grid: divisions of each side of the lattice's fundamental cell."""

DEFAULT_TOL: float = 1e-4
"""Default coverage tolerance: raster coverages within this of the best count as best (raster noise)."""

_MAX_CANDIDATE_POINTS = 4_000_000  # candidates x lattice points held at once in the offset search
_EXACT_TIES = 8  # exact coverage decides between at most this many raster ties


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


def _offsets(lat: Lattice, bbox: tuple[float, float, float, float], steps: int) -> np.ndarray:
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


def check_budget(pattern: str, area: PatternArea, r: float, steps: int = DEFAULT_STEPS, rotations: bool = True,
                 force: bool = False, field: str = "r") -> None:
    """Refuse a placement that would not fit in memory, or (unless ``force``) take absurdly long.

    Estimated from the area's bounding box and ``r`` alone, before anything is allocated.

    Per rotation the lattice has at most ``len(basis) (H / py + 3) (W / px + 4)`` points in the bounding box
    ``W x H`` (the rows and columns :func:`~amronet.patterns.lattices.lattice_points` covers) and the search at most
    ``(steps + 4 len(basis)) (steps + 2 len(basis))`` candidate offsets.

    Raises:
        AmronetError: ``FIELD: ...`` naming the lattice points, the memory or the work, and the fix.
    """
    lat = lattice_basis(pattern, check_pattern(pattern, r))
    x0, y0, x1, y1 = area.bounds
    points = work = 0.0
    k = len(lat.basis)
    offsets = (int(steps) + 4 * k) * (int(steps) + 2 * k)
    for rotated in (False, True) if rotations else (False,):
        w, h = (y1 - y0, x1 - x0) if rotated else (x1 - x0, y1 - y0)
        n = k * (h / lat.py + 3) * (w / lat.px + 4)
        points += n
        work += n * offsets
    where = f"the {pattern} pattern at r = {r:g} m over {x1 - x0:g} m x {y1 - y0:g} m"
    fix = "use a larger r or a smaller area"
    limits.check_memory(points * (limits.BYTES_PER_LATTICE_POINT + offsets * limits.BYTES_PER_LATTICE_CANDIDATE),
                        field, f"{where} ({limits.format_count(points)} lattice points)", fix, error=AmronetError)
    limits.check_work(work, limits.MAX_PATTERN_WORK, field,
                      f"{where} ({limits.format_count(points)} lattice points x {offsets} candidate offsets)",
                      f"{fix} (or fewer --steps)", force, error=AmronetError)


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
    area: AreaLike,
    r: float,
    *,
    mask: np.ndarray | None = None,
    steps: int = DEFAULT_STEPS,
    rotations: bool = True,
    tol: float = DEFAULT_TOL,
    force: bool = False,
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
        force: Acknowledge a search the resource guard finds absurdly long (:func:`check_budget`).

    Returns:
        The placement; if no candidate is connected (possible on masks with obstacles) the best one, reported
        with ``connected=False``. An area too small to hold a node gives an empty placement.

    Raises:
        ValueError: Unknown pattern, ``r`` not finite and positive, ``steps < 1``, ``tol`` outside ``[0, 1)``,
            or a bad area (see :func:`as_area`).
        AmronetError: The lattice would not fit in memory, or the search would take absurdly long without
            ``force`` (:func:`check_budget`).
    """
    r = check_pattern(pattern, r)
    if not (isinstance(steps, int | np.integer) and steps >= 1):
        raise ValueError(f"steps must be an integer >= 1, got {steps!r}")
    if not (0 <= tol < 1):
        raise ValueError(f"tol must be in [0, 1), got {tol!r}")
    pa = as_area(area, mask=mask, r=r)
    check_budget(pattern, pa, r, int(steps), rotations, force)
    lat = lattice_basis(pattern, r)
    bounds = pa.bounds
    if pa.rectangle is None:  # nodes exactly on the far edge of the mask lie in no cell: snap just inside
        eps = 1e-6 * pa.omap.resolution
        bounds = (bounds[0] + eps, bounds[1] + eps, bounds[2] - eps, bounds[3] - eps)
    cands: list[_Candidate] = []
    sel_of: dict[int, np.ndarray] = {}
    frames = {}
    for rotated in (False, True) if rotations else (False,):
        bbox = pattern_bbox(bounds, rotated)
        p, u, j = lattice_points(lat, bbox)
        offs = _offsets(lat, bbox, int(steps))
        frames[rotated] = (p, u, j)
        chunk = max(1, _MAX_CANDIDATE_POINTS // max(len(p), 1))
        for s in range(0, len(offs), chunk):
            o = offs[s : s + chunk]
            inside = pa.inside(to_world(p[None, :, :] + o[:, None, :], rotated))
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
        c.xy, c.connector = lattice_nodes(pattern, p[sel] + c.offset, u[sel], j[sel], c.rotated, pa.inside)
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
    ox, oy = to_world(best.offset, best.rotated)
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
    area: AreaLike,
    r: float,
    patterns: Sequence[str] = PATTERNS,
    **kwargs: Any,
) -> dict[str, Placement]:
    """Place several patterns in one area (prepared once); keyword arguments go to :func:`place`.

    Returns:
        Pattern name to placement, in the order of ``patterns``.
    """
    mask = kwargs.pop("mask", None)
    pa = as_area(area, mask=mask, r=check_pattern(patterns[0] if patterns else PATTERNS[0], r))
    return {name: place(name, pa, r, **kwargs) for name in patterns}
