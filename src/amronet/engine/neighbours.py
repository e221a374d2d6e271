"""Fixed-radius neighbour tables in 2-D: the unit-disk graph of N points as a symmetric CSR, in numba.

:func:`neighbour_csr` links ``i != j`` exactly when ``dx * dx + dy * dy <= r * r`` evaluated in float64
(``dx = x_j - x_i``, ``dy = y_j - y_i``; distance ``<= r``, inclusive) and returns the CSR arrays
``(indptr, indices, dist)``, every row's column indices ascending, ``dist = sqrt(dx * dx + dy * dy)``. The
result is bit-for-bit deterministic: no hashing, every row written by one thread, and every float computed by a
fixed formula from the two points alone (``d(i, j)`` and ``d(j, i)`` are the same bits, since negation is exact).

How the search works, and what it costs: :mod:`amronet.engine.neighbour_search`.

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
from numba import uint64 as _u  # unsigned indices: numba then skips its negative-index wraparound code

from amronet.engine.neighbour_search import rows_threaded, search_kernel, sorted_table
from amronet.threads import LOCK, use_threads

__all__ = ["GroupIds", "neighbour_csr", "neighbour_csr_checked", "pairs_from_csr", "search_kernel"]

_INT32_MAX = int(np.iinfo(np.int32).max)  # most points a table holds (its column indices are int32)


@njit(cache=True)
def _pairs(indptr, indices):  # pragma: no cover - numba
    n = indptr.shape[0] - 1
    first = np.empty(n, np.int64)  # first entry above the diagonal of every (ascending) row: binary search
    m = 0
    for i in range(n):
        lo = indptr[_u(i)]
        hi = indptr[_u(i + 1)]
        end = hi
        while lo < hi:
            mid = (lo + hi) >> 1
            if indices[_u(mid)] <= i:
                lo = mid + 1
            else:
                hi = mid
        first[_u(i)] = lo
        m += end - lo
    out = np.empty((m, 2), np.int64)
    p = 0
    for i in range(n):
        for k in range(first[_u(i)], indptr[_u(i + 1)]):
            out[_u(p), 0] = i
            out[_u(p), 1] = indices[_u(k)]
            p += 1
    return out


# --------------------------------------------------------------------------------------------------------
# public API
# --------------------------------------------------------------------------------------------------------


def neighbour_csr(xy: np.ndarray, r: float, groups: np.ndarray | None = None
                  ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Symmetric CSR of all pairs of points within distance ``r`` of each other (the unit-disk graph).

    ``i != j`` are linked iff ``dx * dx + dy * dy <= r * r`` in float64 (inclusive: points exactly ``r``
    apart along an axis are linked) and, with ``groups``, they belong to the same group. Deterministic bit for
    bit; with groups, every group's rows are exactly those of :func:`neighbour_csr` of the group's points alone
    (shifted by the group's first index when the groups are contiguous blocks): several runs can share one table.

    Args:
        xy: Positions ``(N, 2)``, all finite (converted to float64).
        r: Link radius, positive and finite.
        groups: Group id of every point ``(N,)``, integers in ``[0, G)``; points of different groups are never
            linked. ``None``: one group.

    Returns:
        ``(indptr, indices, dist)``: ``indptr`` int64 ``(N + 1,)``; ``indices`` int32 ``(nnz,)``, each row's
        column indices ascending, no self loops; ``dist`` float64 ``(nnz,)``, ``sqrt(dx * dx + dy * dy)``.
        ``scipy.sparse.csr_matrix((dist, indices, indptr), shape=(N, N))`` is the weighted adjacency.

    Raises:
        ValueError: If ``r`` is not positive and finite, or ``xy`` is not ``(N, 2)``, has non-finite entries
            or ``2**31`` rows or more, or ``groups`` does not give every point an id in ``[0, G)``.
    """
    r = float(r)
    if not (r > 0.0 and math.isfinite(r)):
        raise ValueError(f"r must be positive and finite, got {r!r}")
    xy = np.ascontiguousarray(xy, dtype=np.float64)
    if xy.ndim != 2 or xy.shape[1] != 2:
        raise ValueError(f"xy must have shape (N, 2), got {xy.shape}")
    return neighbour_csr_checked(xy, r, GroupIds.of(groups, xy.shape[0]))


class GroupIds:
    """Checked group ids of ``n`` points for :func:`neighbour_csr_checked`: ``ids`` int64 ``(n,)``, ``count`` groups.

    A caller that builds a table every step (the radio medium) checks its groups once with :meth:`of` and keeps the
    result.
    """

    __slots__ = ("count", "ids", "source")

    def __init__(self, ids: np.ndarray, count: int, source: np.ndarray | None) -> None:
        self.ids = ids
        self.count = count
        self.source = source
        """The array the ids were checked from (``None``: one group)."""

    @classmethod
    def of(cls, groups: np.ndarray | None, n: int) -> GroupIds:
        """Check ``groups`` (``None``: one group) for ``n`` points.

        Raises:
            ValueError: ``n`` is ``2**31`` or more, or ``groups`` does not give every point an integer id ``>= 0``.
        """
        if n > _INT32_MAX:
            raise ValueError(f"at most 2**31 - 1 points, got {n}")
        if groups is None:
            return cls(np.zeros(n, dtype=np.int64), 1, None)
        ids = np.ascontiguousarray(groups, dtype=np.int64)
        if ids.shape != (n,) or (n and ids.min() < 0):
            raise ValueError(f"groups must be {n} integers >= 0, got shape {ids.shape}")
        return cls(ids, int(ids.max()) + 1 if n else 1, groups)


def neighbour_csr_checked(xy: np.ndarray, r: float, groups: GroupIds) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """:func:`neighbour_csr` for inputs checked beforehand, without its per-call checks.

    For a few dozen points the checks cost more than the search (the radio medium builds a table every step).

    Args:
        xy: Positions, float64 C-contiguous ``(N, 2)``.
        r: Link radius, a positive finite float.
        groups: The points' checked group ids (:meth:`GroupIds.of` for these ``N`` points).

    Raises:
        ValueError: ``xy`` has non-finite coordinates.
    """
    if use_threads(len(xy)):
        ok, qp, qi, sidx, sx, sy = sorted_table(xy, r, groups.ids, groups.count)
        if ok:
            with LOCK:
                return rows_threaded(qp, qi, sidx, sx, sy)
    else:
        ok, indptr, indices, dist = search_kernel(xy, r, groups.ids, groups.count)
        if ok:
            return indptr, indices, dist
    raise ValueError("xy has non-finite coordinates")


def pairs_from_csr(indptr: np.ndarray, indices: np.ndarray) -> np.ndarray:
    """The undirected links ``i < j`` of a symmetric CSR, ordered by ``i``, then by ``j``.

    Args:
        indptr: Row pointers ``(N + 1,)``.
        indices: Column indices ``(nnz,)``, each row's ascending (as :func:`neighbour_csr` returns them).

    Returns:
        ``(M, 2)`` int64 array of the entries above the diagonal, as pairs ``(i, j)`` with ``i < j``.
    """
    indptr = np.ascontiguousarray(indptr, dtype=np.int64)
    indices = np.ascontiguousarray(indices)
    if indices.dtype != np.int32:
        indices = indices.astype(np.int64, copy=False)
    return _pairs(indptr, indices)
