"""The area patterns are placed in: a closed rectangle, or the counted cells of a map (:class:`PatternArea`)."""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from fractions import Fraction
from typing import TypeAlias

import numpy as np

from amronet.engine.coverage import CoverageArea
from amronet.world.occupancy import FREE, OccupancyMap

__all__ = ["AreaLike", "PatternArea", "as_area", "in_rectangle"]


def in_rectangle(xy: np.ndarray, w: float, h: float) -> np.ndarray:
    """Boolean ``xy.shape[:-1]``: which points lie in the closed rectangle ``[0, w] x [0, h]``.

    The test is loose by ``1e-9`` of the longer side, so that nodes computed to lie on an edge count.
    """
    xy = np.asarray(xy, dtype=float)
    eps = 1e-9 * max(w, h)
    x, y = xy[..., 0], xy[..., 1]
    return (x >= -eps) & (x <= w + eps) & (y >= -eps) & (y <= h + eps)


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
            return in_rectangle(xy, *self.rectangle)
        rows, cols = self.omap.world_to_cell(xy)
        nr, nc = self.mask.shape
        ok = (rows >= 0) & (rows < nr) & (cols >= 0) & (cols < nc)
        out = np.zeros(ok.shape, dtype=bool)
        out[ok] = self.mask[rows[ok], cols[ok]]
        return out


AreaLike: TypeAlias = tuple[float, float] | OccupancyMap | tuple[OccupancyMap, np.ndarray] | PatternArea
"""What :func:`as_area` accepts: ``(width, height)``, a map, ``(map, mask)`` or a prepared area."""


def _common_cell(w: float, h: float) -> float:
    """The largest length dividing both sides, which must be at least ``max(w, h) / 2048``."""
    fw, fh = Fraction(w).limit_denominator(2048), Fraction(h).limit_denominator(2048)
    den = math.lcm(fw.denominator, fh.denominator)
    g = float(Fraction(math.gcd(int(fw * den), int(fh * den)), den))
    if abs(float(fw) - w) > 1e-9 * w or abs(float(fh) - h) > 1e-9 * h or max(w, h) / g > 2048:
        raise ValueError(f"rectangle sides {w:g} x {h:g} m need a common divisor of at least 1/2048 of the longer side")
    return g


def as_area(
    area: AreaLike,
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
