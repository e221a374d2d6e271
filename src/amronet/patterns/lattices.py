"""The four infinite patterns as lattices, their densities, and their nodes in a rectangle (paper 2.3).

A lattice lives in its *pattern frame*; the world frame is the pattern frame, or it turned by +90 degrees.
The r-strip's rows are joined by *connectors* (see :mod:`amronet.patterns`).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from amronet import limits
from amronet.errors import AmronetError
from amronet.patterns.area import in_rectangle

__all__ = ["DENSITY", "PATTERNS", "estimate", "lattice"]

PATTERNS: tuple[str, ...] = ("r-strip", "hexagonal", "square", "triangular")
"""The pattern names, in the paper's order (sparsest first)."""

DENSITY: dict[str, float] = {"r-strip": 0.536, "hexagonal": 0.77, "square": 1.0, "triangular": 1.155}
"""Nodes per ``r**2`` of each infinite pattern (paper section 2.3)."""

_S3 = math.sqrt(3.0)


@dataclass(frozen=True)
class Lattice:
    """Lattice ``basis + i * (px, 0) + j * (sx, py)`` in the pattern frame."""

    px: float
    sx: float
    py: float
    basis: tuple[tuple[float, float], ...]


def lattice_basis(pattern: str, r: float) -> Lattice:
    """The lattice of ``pattern`` at link length ``r`` in its own frame."""
    if pattern == "r-strip":
        return Lattice(r, r / 2, (1 + _S3 / 2) * r, ((0.0, 0.0),))
    if pattern == "hexagonal":  # honeycomb: two nodes per cell, a vertical edge (0, 0)-(0, r)
        return Lattice(_S3 * r, _S3 / 2 * r, 1.5 * r, ((0.0, 0.0), (0.0, r)))
    if pattern == "square":
        return Lattice(r, 0.0, r, ((0.0, 0.0),))
    return Lattice(r, r / 2, _S3 / 2 * r, ((0.0, 0.0),))


def check_pattern(pattern: str, r: float) -> float:
    """Check a pattern name and link length; return the length as a float (ValueError if either is bad)."""
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
    r = check_pattern(pattern, r)
    if not (math.isfinite(area_m2) and area_m2 >= 0):
        raise ValueError(f"area_m2 must be a finite number >= 0, got {area_m2!r}")
    return math.ceil(DENSITY[pattern] * area_m2 / r**2 - 1e-9)


def to_world(p: np.ndarray, rotated: bool) -> np.ndarray:
    """Pattern-frame points in the world frame (a quarter turn when ``rotated``)."""
    return np.stack([-p[..., 1], p[..., 0]], axis=-1) if rotated else p


def pattern_bbox(bounds: tuple[float, float, float, float], rotated: bool) -> tuple[float, float, float, float]:
    """A world bounding box ``(x0, y0, x1, y1)`` in the pattern frame."""
    x0, y0, x1, y1 = bounds
    return (y0, -x1, y1, -x0) if rotated else bounds


def lattice_points(lat: Lattice, bbox: tuple[float, float, float, float]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
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


def lattice_nodes(
    pattern: str, p: np.ndarray, u: np.ndarray, j: np.ndarray, rotated: bool, inside: Callable
) -> tuple[np.ndarray, np.ndarray]:
    """World positions of the selected pattern-frame nodes plus, for the r-strip, its connectors."""
    xy = to_world(p, rotated)
    conn = np.zeros(len(xy), dtype=bool)
    if pattern == "r-strip" and len(p):
        c = _strip_connectors(p, u, j, lambda q: inside(to_world(q, rotated)))
        xy = np.concatenate([xy, to_world(c, rotated)])
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
        offset: World position of the lattice node ``i = j = 0`` (as :attr:`~amronet.patterns.Placement.offset`).
        rotated: Turn the pattern by 90 degrees (counter-clockwise).

    Returns:
        ``(xy, connector)``: positions ``(N, 2)`` and a boolean mask of the r-strip's connectors.

    Raises:
        ValueError: Unknown pattern or ``r`` not finite and positive.
        AmronetError: The lattice would not fit in the memory available (``BYTES_PER_LATTICE_POINT`` per point).
    """
    r = check_pattern(pattern, r)
    bounds = (0.0, 0.0, float(width), float(height))
    lat = lattice_basis(pattern, r)
    w, h = (float(height), float(width)) if rotated else (float(width), float(height))
    points = len(lat.basis) * (abs(h) / lat.py + 3) * (abs(w) / lat.px + 4)
    limits.check_memory(points * limits.BYTES_PER_LATTICE_POINT, "r",
                        f"the {pattern} lattice at r = {r:g} m over {width:g} m x {height:g} m "
                        f"({limits.format_count(points)} points)", "use a larger r or a smaller area",
                        error=AmronetError)

    def inside(q: np.ndarray) -> np.ndarray:
        return in_rectangle(q, width, height)

    ox, oy = (offset[1], -offset[0]) if rotated else offset
    k = math.floor(oy / lat.py)  # reduce the offset into the fundamental cell
    ox, oy = (ox - k * lat.sx) % lat.px, oy - k * lat.py
    p, u, j = lattice_points(lat, pattern_bbox(bounds, rotated))
    p = p + np.array([ox, oy])
    sel = inside(to_world(p, rotated))
    return lattice_nodes(pattern, p[sel], u[sel], j[sel], rotated, inside)
