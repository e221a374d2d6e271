"""The cell-list search behind the neighbour tables (:mod:`amronet.engine.neighbours`), in numba.

How it works (a cell list; at mean degree 11 on one core of the project's 2-core machine, uniform points, 3 000
points take 0.3-0.5 ms and 100 000 take 43-60 ms, as the machine's speed moves):

1. A uniform grid of square cells of side ``h`` a hair larger than ``r`` covers the points' bounding box, and
   the points are counting-sorted into cells (row-major; stable). The margin of ``h`` over ``r`` absorbs every
   float64 rounding of the cell computation, so two linked points are always in the same or in adjacent
   cells. When the box is huge relative to ``r`` the grid is capped at ``4 N`` cells and ``h`` grows (the
   result never depends on ``h``, only the running time does: points crowded into a few clumps far apart
   share coarser cells, e.g. two clumps of 1500 points 10 000 r apart take ~0.5 ms).
   With groups (several runs sharing one table), every group has a grid of its own over the common box, and
   the cells are numbered group by group.
2. Every candidate pair is tested once, in cell order: a point against the later points of its own cell and
   of the cell to its right (one contiguous run of the sorted coordinates), and against the three cells of
   the row above (a second run). The test appends branch-free, so the loop has no unpredictable branch.
3. These "upper" lists are transposed into a full neighbour table per *sorted* point (cache-friendly: linked
   points are close in sorted order), with original indices as entries.
4. The final CSR is one more transposition, by original index: visiting the points ``c = 0, 1, ...`` in
   order and appending ``c`` to the row of each neighbour of ``c`` fills every row in ascending column order,
   with no sorting.
5. Distances are recomputed row by row from the original coordinates, then square-rooted in one vector pass.

A large search (:func:`amronet.threads.use_threads`: tens of thousands of points) does steps 4 and 5 on several
threads instead (:func:`rows_threaded`): every sorted point's row is sorted by original index with its squared
distances, by one thread, then copied to its place in the final table. The result is the same table bit for bit
(the tests compare the two). Steps 4 and 5 are bound by memory latency (the transposition reads and writes all
over the table when the indices do not follow space): for 100 000 uniform points they took 20 ms on one core and
the threaded build 12 ms on two (best of seven calls each; the whole search 43-45 against 34-36 ms).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit, prange
from numba import uint64 as _u  # unsigned indices: numba then skips its negative-index wraparound code

__all__ = ["candidate_rows", "filter_rows", "rows_threaded", "search_kernel", "sorted_table"]

_EPS = 2.0**-52
_MIN_CELL = 1e-150  # below this r * r is subnormal and loses relative precision; cells never get smaller


@njit(cache=True)
def _grid(xy, r, n_groups):  # pragma: no cover - numba
    """Grid over the bounding box: ``(ok, xmin, ymin, inv_h, nx, ny)``; not ``ok`` if xy is not finite.

    With ``n_groups`` groups every group gets a grid of its own over the common box, so the cap on the cells is
    shared out among them.
    """
    n = xy.shape[0]
    xmin = math.inf
    ymin = math.inf
    xmax = -math.inf
    ymax = -math.inf
    for i in range(n):
        x = xy[_u(i), 0]
        y = xy[_u(i), 1]
        if not (math.isfinite(x) and math.isfinite(y)):
            return False, 0.0, 0.0, 0.0, 1, 1
        xmin = min(xmin, x)
        xmax = max(xmax, x)
        ymin = min(ymin, y)
        ymax = max(ymax, y)
    if n == 0:
        return True, 0.0, 0.0, 0.0, 1, 1
    w = xmax - xmin  # overflows to inf only for coordinates near the float64 limit: then a single cell
    hgt = ymax - ymin
    cap = max(4.0 * n / n_groups, 16.0)
    # Relative margin of h over r. A linked pair has |x_j - x_i| <= r (1 + 3 eps); the computed cell
    # coordinates t = (x - xmin) / h carry an absolute error of at most 3 eps * (cells per axis + 1) each.
    # With h >= r (1 + delta) and delta > 3 eps + 6 eps (cells + 1), t_j - t_i < 1, hence adjacent cells.
    h = max(r, _MIN_CELL) * (1.0 + 2.0**-20 + 16.0 * _EPS * cap)
    fx = math.floor(w / h) + 1.0
    fy = math.floor(hgt / h) + 1.0
    if not (fx * fy <= cap):  # huge box relative to r: the smallest cells with (w / h + 1)(hgt / h + 1) <= cap
        s = w + hgt  # > 0 here; the positive root in 1 / h, scaled by s against overflow
        h = max(h, s * (1.0 + math.sqrt(1.0 + 4.0 * (w / s) * (hgt / s) * (cap - 1.0))) / (2.0 * (cap - 1.0)))
        fx = math.floor(w / h) + 1.0
        fy = math.floor(hgt / h) + 1.0
        while fx * fy > cap:  # rounding only: a step or two
            h *= 1.0 + 2.0**-20
            fx = math.floor(w / h) + 1.0
            fy = math.floor(hgt / h) + 1.0
    if fx * fy <= cap:
        return True, xmin, ymin, 1.0 / h, int(fx), int(fy)
    return True, xmin, ymin, 0.0, 1, 1  # non-finite extent


@njit(cache=True)
def _cell_sort(xy, group, n_groups, xmin, ymin, inv_h, nx, ny):  # pragma: no cover - numba
    """Counting sort into cells: starts ``cs`` (cell c is ``cs[c]:cs[c + 1]``), order, sorted coordinates.

    Group ``g`` owns the cells ``g * nx * ny`` to ``(g + 1) * nx * ny - 1``.
    """
    n = xy.shape[0]
    ncell = nx * ny * n_groups
    fnx = float(nx)
    fny = float(ny)
    cell = np.empty(n, np.int64)
    cs = np.zeros(ncell + 2, np.int64)
    for i in range(n):
        tx = (xy[_u(i), 0] - xmin) * inv_h  # >= 0; monotone in x
        ty = (xy[_u(i), 1] - ymin) * inv_h
        ix = int(tx) if tx < fnx else nx - 1  # clamps rounding at the far edge (and NaN from inf * 0)
        iy = int(ty) if ty < fny else ny - 1
        c = group[_u(i)] * nx * ny + iy * nx + ix
        cell[_u(i)] = c
        cs[_u(c + 2)] += 1
    for c in range(ncell):
        cs[_u(c + 2)] += cs[_u(c + 1)]
    sidx = np.empty(n, np.int32)
    sx = np.empty(n)
    sy = np.empty(n)
    for i in range(n):  # cs[c + 1] is the fill pointer of cell c; afterwards cs[c] is its start
        c = cell[_u(i)]
        p = cs[_u(c + 1)]
        cs[_u(c + 1)] = p + 1
        sidx[_u(p)] = i
        sx[_u(p)] = xy[_u(i), 0]
        sy[_u(p)] = xy[_u(i), 1]
    return cs, sidx, sx, sy


@njit(cache=True)
def _upper_pairs(cs, sx, sy, r2, nx, ny, n_groups):  # pragma: no cover - numba
    """For every sorted point a, the later sorted points b within reach: ``pb[ustart[a]:ustart[a + 1]]``.

    Candidates come from the point's own group only (its block of cells).
    """
    n = sx.shape[0]
    cap = 8 * n + 64
    pb = np.empty(cap, np.int32)
    ustart = np.empty(n + 1, np.int64)
    cnt = 0
    for c in range(n_groups * nx * ny):
        ix = c % nx
        iy = (c // nx) % ny
        s0 = cs[_u(c)]
        s1 = cs[_u(c + 1)]
        if s0 == s1:
            continue
        # run 1: the rest of this cell and the cell to the right; run 2: the three cells of the row above
        e1 = cs[_u(c + 2)] if ix + 1 < nx else s1
        lo2 = 0
        hi2 = 0
        if iy + 1 < ny:
            lo2 = cs[_u(c + nx - 1)] if ix > 0 else cs[_u(c + nx)]
            hi2 = cs[_u(c + nx + 2)] if ix + 1 < nx else cs[_u(c + nx + 1)]
        m = s1 - s0
        need = cnt + m * (e1 - s0 + hi2 - lo2) - m * (m + 1) // 2  # candidates of this cell
        if need > cap:  # grown per cell, never inside the hot loops (that would slow them down)
            cap = max(2 * cap, need)
            grown = np.empty(cap, np.int32)
            for q in range(cnt):  # (a loop: numba compiles a slice copy's shape-mismatch message, seconds)
                grown[_u(q)] = pb[_u(q)]
            pb = grown
        for a in range(s0, s1):
            ustart[_u(a)] = cnt
            xa = sx[_u(a)]
            ya = sy[_u(a)]
            for b in range(a + 1, e1):  # branch-free append: write, then advance if linked
                dx = sx[_u(b)] - xa
                dy = sy[_u(b)] - ya
                pb[_u(cnt)] = b
                cnt += dx * dx + dy * dy <= r2
            for b in range(lo2, hi2):
                dx = sx[_u(b)] - xa
                dy = sy[_u(b)] - ya
                pb[_u(cnt)] = b
                cnt += dx * dx + dy * dy <= r2
    ustart[n] = cnt
    return ustart, pb


@njit(cache=True)
def _sorted_point_table(ustart, pb, label):  # pragma: no cover - numba
    """Neighbour table per sorted point: row a is ``qi[qp[a]:qp[a + 1]]``, sorted point b entered as ``label[b]``.

    ``label``: the original indices (``sidx``), or the sorted positions themselves (``0, 1, ...``).
    """
    n = ustart.shape[0] - 1
    npairs = ustart[n]
    qp = np.zeros(n + 1, np.int64)
    for k in range(npairs):  # qp[b + 1] counts b's earlier neighbours first
        qp[_u(pb[_u(k)] + 1)] += 1
    for a in range(n):
        qp[_u(a + 1)] += qp[_u(a)] + ustart[_u(a + 1)] - ustart[_u(a)]
    fill = qp[:n].copy()
    qi = np.empty(qp[n], np.int32)
    for a in range(n):
        u0 = ustart[_u(a)]
        u1 = ustart[_u(a + 1)]
        o = qp[_u(a + 1)] - u1  # row a: earlier neighbours (scattered here by them), then its own upper list
        ia = label[_u(a)]
        for k in range(u0, u1):
            b = pb[_u(k)]
            qi[_u(o + k)] = label[_u(b)]
            f = fill[_u(b)]
            qi[_u(f)] = ia
            fill[_u(b)] = f + 1
    return qp, qi


@njit(cache=True)
def _rank_and_indptr(qp, sidx):  # pragma: no cover - numba
    """Every point's place in the cell order (``rank``) and the final CSR's row pointers."""
    n = sidx.shape[0]
    rank = np.empty(n, np.int32)
    for a in range(n):
        rank[_u(sidx[_u(a)])] = a
    indptr = np.empty(n + 1, np.int64)
    indptr[0] = 0
    for i in range(n):
        a = rank[_u(i)]
        indptr[_u(i + 1)] = indptr[_u(i)] + (qp[_u(a + 1)] - qp[_u(a)])
    return rank, indptr


@njit(cache=True)
def _transpose_by_index(qp, qi, sidx):  # pragma: no cover - numba
    """Final CSR indices: visiting c = 0, 1, ... and appending c to its neighbours' rows sorts every row."""
    n = sidx.shape[0]
    rank, indptr = _rank_and_indptr(qp, sidx)
    fill = indptr[:n].copy()
    indices = np.empty(indptr[n], np.int32)
    for c in range(n):
        a = rank[_u(c)]
        for k in range(qp[_u(a)], qp[_u(a + 1)]):
            row = qi[_u(k)]
            f = fill[_u(row)]
            indices[_u(f)] = c
            fill[_u(row)] = f + 1
    return indptr, indices


@njit(cache=True)
def _distances(xy, indptr, indices):  # pragma: no cover - numba
    """``sqrt(dx * dx + dy * dy)`` of every entry; squared row by row, then one (vectorised) sqrt pass."""
    n = indptr.shape[0] - 1
    nnz = indices.shape[0]
    dist = np.empty(nnz)
    for i in range(n):
        xi = xy[_u(i), 0]
        yi = xy[_u(i), 1]
        for k in range(indptr[_u(i)], indptr[_u(i + 1)]):
            j = indices[_u(k)]
            dx = xy[_u(j), 0] - xi
            dy = xy[_u(j), 1] - yi
            dist[_u(k)] = dx * dx + dy * dy
    for k in range(nnz):
        dist[_u(k)] = math.sqrt(dist[_u(k)])
    return dist


@njit(cache=True)
def search_kernel(xy, r, group, n_groups):  # pragma: no cover - numba
    """The one-thread search, for other kernels: ``(ok, indptr, indices, dist)``, ``ok`` false on non-finite ``xy``.

    ``group``: every point's group id (``n_groups`` of them, ids ``0 .. n_groups - 1``); what
    :func:`neighbour_csr_checked` runs below :data:`~amronet.threads.MIN_ITEMS` points.
    """
    ok, xmin, ymin, inv_h, nx, ny = _grid(xy, r, n_groups)
    if not ok:
        return False, np.zeros(1, np.int64), np.empty(0, np.int32), np.empty(0)
    cs, sidx, sx, sy = _cell_sort(xy, group, n_groups, xmin, ymin, inv_h, nx, ny)
    ustart, pb = _upper_pairs(cs, sx, sy, r * r, nx, ny, n_groups)
    qp, qi = _sorted_point_table(ustart, pb, sidx)
    indptr, indices = _transpose_by_index(qp, qi, sidx)
    return True, indptr, indices, _distances(xy, indptr, indices)


@njit(cache=True, parallel=True)
def rows_threaded(qp, qi, sidx, sx, sy):  # pragma: no cover - numba
    """Steps 4 and 5 on several threads: every row sorted and measured by one thread, then copied into place."""
    n = sidx.shape[0]
    cols = np.empty(qi.shape[0], np.int32)
    sq = np.empty(qi.shape[0])
    for a in prange(n):  # sorted point a's row, by original index (insertion sort: a dozen entries)
        o = qp[_u(a)]
        xa = sx[_u(a)]
        ya = sy[_u(a)]
        for k in range(o, qp[_u(a + 1)]):
            b = qi[_u(k)]
            j = sidx[_u(b)]
            dx = sx[_u(b)] - xa  # the same coordinates as xy[j] - xy[i]: the same bits
            dy = sy[_u(b)] - ya
            d2 = dx * dx + dy * dy
            p = k
            while p > o and cols[_u(p - 1)] > j:
                cols[_u(p)] = cols[_u(p - 1)]
                sq[_u(p)] = sq[_u(p - 1)]
                p -= 1
            cols[_u(p)] = j
            sq[_u(p)] = d2
    rank, indptr = _rank_and_indptr(qp, sidx)
    indices = np.empty(indptr[n], np.int32)
    dist = np.empty(indptr[n])
    for i in prange(n):  # row i is sorted point rank[i]'s row
        a = rank[_u(i)]
        shift = indptr[_u(i)] - qp[_u(a)]
        for k in range(qp[_u(a)], qp[_u(a + 1)]):
            indices[_u(shift + k)] = cols[_u(k)]
            dist[_u(shift + k)] = math.sqrt(sq[_u(k)])
    return indptr, indices, dist


@njit(cache=True)
def sorted_table(xy, r, group, n_groups):  # pragma: no cover - numba
    """Steps 1 to 3, the table per sorted point with entries as sorted positions, for :func:`rows_threaded`."""
    ok, xmin, ymin, inv_h, nx, ny = _grid(xy, r, n_groups)
    if not ok:
        empty = np.empty(0)
        return False, np.zeros(1, np.int64), np.empty(0, np.int32), np.empty(0, np.int32), empty, empty
    cs, sidx, sx, sy = _cell_sort(xy, group, n_groups, xmin, ymin, inv_h, nx, ny)
    ustart, pb = _upper_pairs(cs, sx, sy, r * r, nx, ny, n_groups)
    qp, qi = _sorted_point_table(ustart, pb, np.arange(sidx.shape[0], dtype=np.int32))
    return True, qp, qi, sidx, sx, sy


@njit(cache=True)
def candidate_rows(xy, r, group, n_groups):  # pragma: no cover - numba
    """Steps 1 to 4 of :func:`search_kernel` without the distances: ``(ok, indptr, indices)``, the pairs within ``r``.

    The candidates of :func:`filter_rows` (a skin table, :mod:`amronet.engine.skin_table`).
    """
    ok, xmin, ymin, inv_h, nx, ny = _grid(xy, r, n_groups)
    if not ok:
        return False, np.zeros(1, np.int64), np.empty(0, np.int32)
    cs, sidx, sx, sy = _cell_sort(xy, group, n_groups, xmin, ymin, inv_h, nx, ny)
    ustart, pb = _upper_pairs(cs, sx, sy, r * r, nx, ny, n_groups)
    qp, qi = _sorted_point_table(ustart, pb, sidx)
    indptr, indices = _transpose_by_index(qp, qi, sidx)
    return True, indptr, indices


@njit(cache=True)
def filter_rows(xy, r, cand_indptr, cand_indices, indptr, indices, sq, dist):  # pragma: no cover - numba
    """The table of :func:`search_kernel` at radius ``r`` from candidate rows holding every pair within ``r``.

    Row by row, the candidates (ascending) linked by :func:`search_kernel`'s test ``dx * dx + dy * dy <= r * r``, with
    its distances (the same operations on the same coordinates: the same table bit for bit). Written into
    ``indptr`` ``(N + 1,)`` and the first entries of ``indices``, ``sq`` (scratch) and ``dist``, each as long as the
    candidates; returns ``(indptr, indices, dist)``, the last two cut to the table's length.
    """
    n = cand_indptr.shape[0] - 1
    r2 = r * r
    indptr[0] = 0
    cnt = 0
    for i in range(n):
        xi = xy[_u(i), 0]
        yi = xy[_u(i), 1]
        for k in range(cand_indptr[_u(i)], cand_indptr[_u(i + 1)]):  # branch-free append, as _upper_pairs
            j = cand_indices[_u(k)]
            dx = xy[_u(j), 0] - xi
            dy = xy[_u(j), 1] - yi
            d2 = dx * dx + dy * dy
            indices[_u(cnt)] = j
            sq[_u(cnt)] = d2
            cnt += d2 <= r2
        indptr[_u(i + 1)] = cnt
    for k in range(cnt):
        dist[_u(k)] = math.sqrt(sq[_u(k)])
    return indptr, indices[:cnt], dist[:cnt]
