"""Fixed-radius neighbour tables in 2-D: the unit-disk graph of N points as a symmetric CSR, in numba.

:func:`neighbour_csr` links ``i`` and ``j`` (``i != j``) exactly when ``dx * dx + dy * dy <= r * r`` evaluated
in float64 (``dx = x_j - x_i``, ``dy = y_j - y_i``), i.e. distance ``<= r`` inclusive, and returns the CSR
arrays ``(indptr, indices, dist)`` with every row's column indices ascending and ``dist = sqrt(dx*dx+dy*dy)``.
The result is bit-for-bit deterministic (no threads, no hashing, no order-dependent float arithmetic).

How it works (a cell list, one core):

1. A uniform grid of square cells of side ``h`` slightly larger than ``r`` covers the points' bounding box;
   points are counting-sorted into cells (row-major, stable, so a cell lists its points by ascending index).
   ``h`` exceeds ``r`` by a relative margin that absorbs every float64 rounding in the cell computation, so
   two linked points are always in the same or adjacent cells. When the box is huge relative to ``r`` the
   grid is capped at ``~4 N`` cells and ``h`` grows accordingly (the result never depends on ``h``, only the
   running time does).
2. Every pair is examined once, in sorted order: the points of a cell are tested against the later points
   of the same cell and of the cell to the right, and against the three cells of the row above. These are
   two contiguous runs of the sorted coordinates, scanned branch-free.
3. The pairs are scattered into a CSR in sorted order (cache-friendly: linked points are close there), and
   finally every row is gathered in original order, mapped back to original indices and insertion-sorted
   (rows hold ~10 entries).

Example:
    >>> import numpy as np
    >>> indptr, indices, dist = neighbour_csr(np.array([[0.0, 0.0], [1.0, 0.0], [3.0, 0.0]]), 1.0)
    >>> indptr.tolist(), indices.tolist(), dist.tolist()
    ([0, 1, 2, 2], [1, 0], [1.0, 1.0])
    >>> pairs_from_csr(indptr, indices).tolist()
    [[0, 1]]
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

__all__ = ["neighbour_csr", "pairs_from_csr"]

_EPS = 2.0**-52
_MIN_CELL = 1e-150  # below this, r * r loses relative precision (subnormal); cells never get smaller


@njit(cache=True)
def _grid(xy, r):  # pragma: no cover - numba
    """Bounding box and grid: (status, xmin, ymin, inv_h, nx, ny); status -1 if some coordinate is not finite."""
    n = xy.shape[0]
    xmin = math.inf
    ymin = math.inf
    xmax = -math.inf
    ymax = -math.inf
    for i in range(n):
        x = xy[i, 0]
        y = xy[i, 1]
        if not (math.isfinite(x) and math.isfinite(y)):
            return -1, 0.0, 0.0, 0.0, 1, 1
        xmin = min(xmin, x)
        xmax = max(xmax, x)
        ymin = min(ymin, y)
        ymax = max(ymax, y)
    if n == 0:
        return 0, 0.0, 0.0, 0.0, 1, 1
    w = xmax - xmin  # may overflow to inf for coordinates near the float64 limit: then one cell
    hgt = ymax - ymin
    cap = max(4.0 * n, 16.0)
    # relative margin of h over r: covers the rounding of x - xmin, of the scaling by 1/h (both relative to
    # the grid extent, at most cap cells) and of the distance test itself
    h = max(r, _MIN_CELL) * (1.0 + 2.0**-20 + 16.0 * _EPS * cap)
    fx = math.floor(w / h) + 1.0
    fy = math.floor(hgt / h) + 1.0
    if not (fx * fy <= cap):
        h = max(h, 2.0 * math.sqrt(w * hgt / cap), 2.0 * (w + hgt) / cap)
        fx = math.floor(w / h) + 1.0
        fy = math.floor(hgt / h) + 1.0
        while fx * fy > cap:
            h *= 2.0
            fx = math.floor(w / h) + 1.0
            fy = math.floor(hgt / h) + 1.0
    if fx * fy <= cap:
        return 0, xmin, ymin, 1.0 / h, int(fx), int(fy)
    return 0, xmin, ymin, 0.0, 1, 1  # non-finite extent: everything in one cell


@njit(cache=True)
def _build(xy, r, xmin, ymin, inv_h, nx, ny):  # pragma: no cover - numba
    n = xy.shape[0]
    r2 = r * r
    ncell = nx * ny
    fnx = float(nx)
    fny = float(ny)

    # 1. counting sort into cells (stable: a cell lists its points by ascending index)
    cell = np.empty(n, np.int64)
    cs = np.zeros(ncell + 2, np.int64)
    for i in range(n):
        tx = (xy[i, 0] - xmin) * inv_h
        ty = (xy[i, 1] - ymin) * inv_h
        ix = int(tx) if tx < fnx else nx - 1  # clamps rounding at the far edge (and NaN from inf * 0)
        iy = int(ty) if ty < fny else ny - 1
        c = iy * nx + ix
        cell[i] = c
        cs[c + 2] += 1
    for c in range(ncell):
        cs[c + 2] += cs[c + 1]
    # cs[c + 1] is now the start of cell c; use it as the fill pointer, after which cs[c] is the start of c
    sidx = np.empty(n, np.int64)
    sx = np.empty(n)
    sy = np.empty(n)
    for i in range(n):
        c = cell[i]
        p = cs[c + 1]
        cs[c + 1] = p + 1
        sidx[p] = i
        sx[p] = xy[i, 0]
        sy[p] = xy[i, 1]
    # now cs[c] = start of cell c, cs[c + 1] = end of cell c

    # 2. every pair once, in sorted order: a against later points of its cell and the cell to its right
    # (one run), and against the three cells of the row above (another run); branch-free appends
    cap = max(16, 8 * n)
    pb = np.empty(cap, np.int32)
    pd = np.empty(cap)
    ustart = np.empty(n + 1, np.int64)
    cnt = 0
    for iy in range(ny):
        for ix in range(nx):
            c = iy * nx + ix
            s0 = cs[c]
            s1 = cs[c + 1]
            if s0 == s1:
                continue
            e1 = cs[c + 2] if ix + 1 < nx else s1
            lo2 = 0
            hi2 = 0
            if iy + 1 < ny:
                lo2 = cs[c + nx - 1] if ix > 0 else cs[c + nx]
                hi2 = cs[c + nx + 2] if ix + 1 < nx else cs[c + nx + 1]
            for a in range(s0, s1):
                ustart[a] = cnt
                need = cnt + (e1 - a - 1) + (hi2 - lo2)
                if need > cap:
                    cap = max(2 * cap, need)
                    nb = np.empty(cap, np.int32)
                    nd = np.empty(cap)
                    nb[:cnt] = pb[:cnt]
                    nd[:cnt] = pd[:cnt]
                    pb = nb
                    pd = nd
                xa = sx[a]
                ya = sy[a]
                for b in range(a + 1, e1):
                    dx = sx[b] - xa
                    dy = sy[b] - ya
                    d2 = dx * dx + dy * dy
                    pb[cnt] = b
                    pd[cnt] = d2
                    cnt += d2 <= r2
                for b in range(lo2, hi2):
                    dx = sx[b] - xa
                    dy = sy[b] - ya
                    d2 = dx * dx + dy * dy
                    pb[cnt] = b
                    pd[cnt] = d2
                    cnt += d2 <= r2
    ustart[n] = cnt

    # 3. symmetric CSR in sorted order (linked points are close in it, so the scatter stays in cache)
    qp = np.zeros(n + 1, np.int64)
    for a in range(n):
        qp[a + 1] += ustart[a + 1] - ustart[a]
        for k in range(ustart[a], ustart[a + 1]):
            qp[pb[k] + 1] += 1
    for a in range(n):
        qp[a + 1] += qp[a]
    nnz = qp[n]
    fill = qp[:n].copy()
    qi = np.empty(nnz, np.int32)
    qd = np.empty(nnz)
    for a in range(n):
        for k in range(ustart[a], ustart[a + 1]):
            b = pb[k]
            d = math.sqrt(pd[k])
            qi[fill[a]] = b
            qd[fill[a]] = d
            fill[a] += 1
            qi[fill[b]] = a
            qd[fill[b]] = d
            fill[b] += 1

    # 4. rows in original order, columns mapped back to original indices and insertion-sorted
    rank = np.empty(n, np.int64)
    for a in range(n):
        rank[sidx[a]] = a
    indptr = np.empty(n + 1, np.int64)
    indptr[0] = 0
    for i in range(n):
        a = rank[i]
        indptr[i + 1] = indptr[i] + (qp[a + 1] - qp[a])
    indices = np.empty(nnz, np.int32)
    dist = np.empty(nnz)
    for i in range(n):
        a = rank[i]
        o = indptr[i]
        m = 0
        for k in range(qp[a], qp[a + 1]):
            j = np.int32(sidx[qi[k]])
            d = qd[k]
            t = m - 1
            while t >= 0 and indices[o + t] > j:
                indices[o + t + 1] = indices[o + t]
                dist[o + t + 1] = dist[o + t]
                t -= 1
            indices[o + t + 1] = j
            dist[o + t + 1] = d
            m += 1
    return indptr, indices, dist


def neighbour_csr(xy: np.ndarray, r: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Symmetric CSR of all pairs of points within distance ``r`` of each other (the unit-disk graph).

    ``i != j`` are linked iff ``dx * dx + dy * dy <= r * r`` in float64 (inclusive). Deterministic bit for bit.

    Args:
        xy: Positions ``(N, 2)`` (any float dtype; converted to float64), all finite.
        r: Link radius, ``> 0``.

    Returns:
        ``(indptr, indices, dist)``: ``indptr`` int64 ``(N + 1,)``, ``indices`` int32 ``(nnz,)`` with each
        row's column indices ascending and no self loops, ``dist`` float64 ``(nnz,)`` with
        ``sqrt(dx * dx + dy * dy)``. ``scipy.sparse.csr_matrix((dist, indices, indptr), shape=(N, N))`` is
        the weighted adjacency.

    Raises:
        ValueError: ``r`` is not a positive finite number, ``xy`` is not ``(N, 2)``, has non-finite entries
            or more than ``2**31 - 1`` rows.
    """
    r = float(r)
    if not (r > 0.0 and math.isfinite(r)):
        raise ValueError(f"r must be a positive finite number, got {r!r}")
    xy = np.ascontiguousarray(xy, dtype=np.float64)
    if xy.ndim != 2 or xy.shape[1] != 2:
        raise ValueError(f"xy must have shape (N, 2), got {xy.shape}")
    if xy.shape[0] > np.iinfo(np.int32).max:
        raise ValueError("xy has more than 2**31 - 1 points")
    status, xmin, ymin, inv_h, nx, ny = _grid(xy, r)
    if status < 0:
        raise ValueError("xy has non-finite coordinates")
    return _build(xy, r, xmin, ymin, inv_h, nx, ny)


@njit(cache=True)
def _pairs(indptr, indices):  # pragma: no cover - numba
    n = indptr.shape[0] - 1
    m = 0
    for i in range(n):
        for k in range(indptr[i], indptr[i + 1]):
            m += indices[k] > i
    out = np.empty((m, 2), np.int64)
    p = 0
    for i in range(n):
        for k in range(indptr[i], indptr[i + 1]):
            j = indices[k]
            if j > i:
                out[p, 0] = i
                out[p, 1] = j
                p += 1
    return out


def pairs_from_csr(indptr: np.ndarray, indices: np.ndarray) -> np.ndarray:
    """The undirected links ``i < j`` of a symmetric CSR, ordered by ``i`` then by ``j``.

    Args:
        indptr: Row pointers ``(N + 1,)``.
        indices: Column indices ``(nnz,)``, each row's ascending (as :func:`neighbour_csr` returns them).

    Returns:
        ``(M, 2)`` int64 array of pairs ``(i, j)`` with ``i < j``: the entries above the diagonal.
    """
    indptr = np.ascontiguousarray(indptr, dtype=np.int64)
    indices = np.ascontiguousarray(indices)
    if indices.dtype not in (np.int32, np.int64):
        indices = indices.astype(np.int64)
    return _pairs(indptr, indices)
