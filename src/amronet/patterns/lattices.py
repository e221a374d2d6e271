"""The four infinite patterns as lattices, their densities, and their nodes in a rectangle (paper 2.3).

A lattice lives in its *pattern frame*; the world frame is the pattern frame, or it turned by +90 degrees.
The r-strip's rows are joined by *connectors* (see :mod:`amronet.patterns`).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from numba import njit

import amronet.limits as limits
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

    The candidates are the midpoints between a node and a node of the next row half a step to its left or right,
    taken by row, then by half-step column; one joins two runs not yet joined (rows are runs of nodes a step
    apart) where ``ok`` allows a node. Compiled (:func:`_strip_candidates`, :func:`_strip_join`): the pattern search
    calls this for thousands of candidate offsets.

    Args:
        p: Row nodes ``(n, 2)``.
        u: Their half-step columns.
        j: Their rows.
        ok: Whether pattern-frame points may hold a node.

    Returns:
        Connector positions ``(m, 2)``; on a rectangle exactly one per pair of adjacent non-empty rows.
    """
    if len(p) == 0:
        return np.empty((0, 2))
    ks, qs, parent = _strip_candidates(np.asarray(u, dtype=np.int64), np.asarray(j, dtype=np.int64))
    if len(ks) == 0:
        return np.empty((0, 2))
    mids = (p[ks] + p[qs]) / 2
    return mids[_strip_join(ks, qs, np.asarray(ok(mids), dtype=np.bool_), parent)]


@njit(cache=True)
def _root(parent, a):  # pragma: no cover - numba
    while parent[a] != a:
        parent[a] = parent[parent[a]]
        a = parent[a]
    return a


@njit(cache=True)
def _strip_candidates(u, j):  # pragma: no cover - numba
    """The rows' runs (``parent``, a union-find forest) and the candidate pairs ``(ks, qs)`` in their order.

    Nodes are told apart by ``(u, j)``; a repeated one stands for the last node with it, as a dictionary keyed
    by ``(u, j)`` would have it.
    """
    n = u.shape[0]
    umin, umax, jmin, jmax = u.min(), u.max(), j.min(), j.max()
    width = umax - umin + 1
    cell = np.full((jmax - jmin + 1, width), -1, np.int64)
    for k in range(n):
        cell[j[k] - jmin, u[k] - umin] = k
    parent = np.arange(n)
    seen = np.zeros((jmax - jmin + 1, width), np.bool_)
    order = np.empty(n, np.int64)  # the nodes that stand for their (u, j), once each, in order of first sight
    m = 0
    for k in range(n):
        if not seen[j[k] - jmin, u[k] - umin]:
            seen[j[k] - jmin, u[k] - umin] = True
            order[m] = cell[j[k] - jmin, u[k] - umin]
            m += 1
    order = order[:m]
    for k in order:  # runs: a node joins the node a step to its right
        a = u[k] - umin + 2
        if a < width:
            q = cell[j[k] - jmin, a]
            if q >= 0:
                parent[_root(parent, q)] = _root(parent, k)
    ks = np.empty(2 * m, np.int64)
    qs = np.empty(2 * m, np.int64)
    key = np.empty(2 * m, np.int64)
    c = 0
    span = 2 * width + 4
    for k in order:
        row = j[k] - jmin + 1
        if row > jmax - jmin:
            continue
        for du in (-1, 1):
            a = u[k] - umin + du
            if 0 <= a < width:
                q = cell[row, a]
                if q >= 0:
                    ks[c] = k
                    qs[c] = q
                    # by row, then half-step column 2 u + du, then node: the order of sorting (j, 2 u + du, k, q)
                    key[c] = ((j[k] - jmin) * span + (2 * (u[k] - umin) + du + 1)) * n + k
                    c += 1
    by = np.argsort(key[:c], kind="mergesort")
    return ks[:c][by], qs[:c][by], parent


@njit(cache=True)
def _strip_join(ks, qs, good, parent):  # pragma: no cover - numba
    """The candidates that join two runs not yet joined, taken in order (``parent`` is updated)."""
    out = np.empty(ks.shape[0], np.int64)
    m = 0
    for c in range(ks.shape[0]):
        if good[c]:
            a = _root(parent, ks[c])
            b = _root(parent, qs[c])
            if a != b:
                parent[b] = a
                out[m] = c
                m += 1
    return out[:m]


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
