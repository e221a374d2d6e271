"""Shrinking an instance without changing its optimum: merged and implied coverage rows, dominated sites.

* **Merged rows.** Sample cells covered by the same set of sites give the same constraint: one row each.
* **Implied rows.** A row whose set of sites contains another row's set is satisfied whenever that row is: only the
  minimal rows stay. Checked first between rows of neighbouring cells (cheap: crossing one disk's edge adds or
  drops one site), then between all remaining rows when that product is small enough.
* **Dominated sites.** Site ``j`` is dominated by site ``k`` when ``k`` covers every row ``j`` covers *and* ``k``
  links to every site ``j`` links to (except ``k`` itself) and to a base station when ``j`` does. Replacing ``j``
  by ``k`` in any placement then keeps it covering and connected (coverage alone is not enough: a site that covers
  less may be the one relay that joins two parts), so some optimum avoids ``j``; sites are removed one at a time,
  each only while its dominator stays. A site that covers no remaining row and whose every neighbour links to a
  base station is dominated by the base stations themselves. Removing sites shrinks rows, so the three steps repeat
  until nothing changes.

Every step keeps at least one optimal placement of the instance, so the optimum and every lower bound of the reduced
problem are those of the instance.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np
import scipy.sparse as sp

from amronet.optimum.instance import Instance

__all__ = ["Reduced", "distinct_rows", "reduce_instance"]

FULL_CHECK_PAIRS = 2_000_000_000
"""Most (row, row) pairs sharing a site the full implied-row check looks at (beyond, neighbouring cells' rows only)."""

CHECK_BLOCK = 20_000_000
"""Rows times rows of one block of the full implied-row check (bounds its memory)."""


@dataclass(frozen=True, eq=False)
class Reduced:
    """The reduced problem.

    Attributes:
        rows: CSR ``(m, k)``: the minimal distinct coverage rows over the kept sites.
        keep: The kept sites, indices into the instance's sites ``(k,)``.
        links: Symmetric CSR ``(k, k)`` of the links between kept sites.
        base_linked: ``(k,)``: the kept site links to a base station.
        replaced_by: Per site of the instance, the site that took its place when it was removed (an instance index;
            -1: kept, or removed with nothing in its place).
        stats: What each step did (counts) and its time.
    """

    rows: sp.csr_matrix
    keep: np.ndarray
    links: sp.csr_matrix
    base_linked: np.ndarray
    replaced_by: np.ndarray
    stats: dict = field(default_factory=dict)

    @property
    def n(self) -> int:
        """Number of kept sites."""
        return len(self.keep)

    def from_instance(self, sites: np.ndarray) -> np.ndarray:
        """A placement given as instance sites (indices) as a mask over the kept sites, removed sites replaced.

        The result need not cover or connect as the original did (a site's dominator was checked against the rows and
        links of its pass): check it.
        """
        where = np.full(len(self.replaced_by), -1, dtype=np.int64)
        where[self.keep] = np.arange(len(self.keep))
        out = np.zeros(self.n, dtype=bool)
        for j in np.asarray(sites, dtype=np.int64).tolist():
            hops = 0
            while where[j] < 0 and self.replaced_by[j] >= 0 and hops < len(where):
                j, hops = int(self.replaced_by[j]), hops + 1
            if where[j] >= 0:
                out[where[j]] = True
        return out


def reduce_instance(inst: Instance, dominate: bool = True) -> Reduced:
    """Merge rows, drop implied rows and dominated sites until nothing changes (see the module docstring).

    Args:
        inst: The instance.
        dominate: Remove dominated sites (``False``: rows only, for measuring what domination buys).
    """
    t0 = time.perf_counter()
    groups, rows = distinct_rows(inst.cover)
    stats = {"cells": int(inst.cover.shape[0]), "distinct_rows": int(rows.shape[0]), "sites": inst.n_sites}
    rows = rows[_locally_minimal(inst, groups, rows)]
    stats["locally_minimal_rows"] = int(rows.shape[0])
    replaced_by = np.full(inst.n_sites, -1, dtype=np.int64)
    keep = np.flatnonzero(np.isfinite(inst.hops()))  # a site with no chain of links to a base is never used
    links = inst.links.tocsr()[keep][:, keep].tocsr()
    base = inst.base_linked[keep]
    rows = rows[:, keep].tocsr()
    passes = 0
    while True:
        passes += 1
        rows = distinct_rows(rows)[1]
        rows = rows[_minimal(rows)]
        if not dominate:
            break
        drop, by = _dominated(rows, links, base)
        if not drop.any():
            break
        replaced_by[keep[drop]] = np.where(by[drop] >= 0, keep[np.maximum(by[drop], 0)], -1)
        kept = ~drop
        keep, rows, links, base = keep[kept], rows[:, kept].tocsr(), links[kept][:, kept].tocsr(), base[kept]
    rows.sort_indices()
    links.sort_indices()
    stats.update(minimal_rows=int(rows.shape[0]), kept_sites=len(keep), dominated_sites=inst.n_sites - len(keep),
                 passes=passes, seconds=round(time.perf_counter() - t0, 3))
    return Reduced(rows=rows, keep=keep, links=links, base_linked=base, replaced_by=replaced_by, stats=stats)


def _row_keys(m: sp.csr_matrix) -> np.ndarray:
    """Two 64-bit hashes and the length of every row's set of columns, as one ``(rows, 3)`` array."""
    rng = np.random.default_rng(0x0B7)  # fixed: the same rows group the same way every time
    n = m.shape[1]
    w1 = rng.integers(0, 2**63, size=n, dtype=np.uint64) | np.uint64(1)
    w2 = rng.integers(0, 2**63, size=n, dtype=np.uint64)
    lengths = np.diff(m.indptr)
    nonempty = lengths > 0
    starts = m.indptr[:-1][nonempty]
    keys = np.zeros((m.shape[0], 3), dtype=np.uint64)
    if len(m.indices):
        keys[nonempty, 0] = np.add.reduceat(w1[m.indices], starts)  # wraps modulo 2**64
        keys[nonempty, 1] = np.bitwise_xor.reduceat(w2[m.indices] * np.uint64(0x9E3779B97F4A7C15), starts)
    keys[:, 2] = lengths
    return keys


def distinct_rows(m: sp.csr_matrix) -> tuple[np.ndarray, sp.csr_matrix]:
    """Group equal rows: ``(group of every row, one row per group)``; groups are numbered by first occurrence.

    Rows are grouped by hashes, then every row is compared with its group's first row, entry by entry; a collision
    (never seen) falls back to grouping by the rows' exact contents.
    """
    m = m.tocsr()
    m.sort_indices()
    keys = _row_keys(m)
    _, first, inverse = np.unique(keys, axis=0, return_index=True, return_inverse=True)
    inverse = inverse.ravel()
    order = np.argsort(first, kind="stable")
    rank = np.empty_like(order)
    rank[order] = np.arange(len(order))
    groups = rank[inverse]
    reps = first[order]
    if not _same_as_rep(m, reps[groups]):
        exact: dict[bytes, int] = {}
        groups = np.array([exact.setdefault(m.indices[m.indptr[i]:m.indptr[i + 1]].tobytes(), len(exact))
                           for i in range(m.shape[0])], dtype=np.int64)
        reps = np.unique(groups, return_index=True)[1]
    return groups, m[reps]


def _same_as_rep(m: sp.csr_matrix, rep_of_row: np.ndarray) -> bool:
    """Whether every row equals the row ``rep_of_row`` names, entry by entry (rows of equal length assumed)."""
    lengths = np.diff(m.indptr)
    if not np.array_equal(lengths, lengths[rep_of_row]):
        return False
    offsets = np.arange(len(m.indices)) - np.repeat(m.indptr[:-1], lengths)
    mine = m.indices
    theirs = m.indices[np.repeat(m.indptr[:-1][rep_of_row], lengths) + offsets]
    return bool(np.array_equal(mine, theirs))


def _subset_pairs(m: sp.csr_matrix, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """For pairs of rows ``(a[k], b[k])``: whether row ``a[k]``'s set lies within row ``b[k]``'s."""
    if len(a) == 0:
        return np.zeros(0, dtype=bool)
    common = np.asarray(m[a].multiply(m[b]).sum(axis=1)).ravel()
    return common == np.diff(m.indptr)[a]


def _locally_minimal(inst: Instance, groups: np.ndarray, rows: sp.csr_matrix) -> np.ndarray:
    """Rows no row of a neighbouring sample cell (4-neighbours) is a strict subset of."""
    shape = inst.omap.shape
    where = np.full(shape[0] * shape[1], -1, dtype=np.int64)
    where[inst.cells] = groups
    grid = where.reshape(shape)
    pairs = []
    for a, b in ((grid[:, :-1], grid[:, 1:]), (grid[:-1, :], grid[1:, :])):
        ok = (a >= 0) & (b >= 0) & (a != b)
        pairs.append(np.stack([a[ok], b[ok]], axis=1))
    p = np.unique(np.vstack([*pairs, np.zeros((0, 2), np.int64)]), axis=0)
    p = np.vstack([p, p[:, ::-1]])  # both directions
    lengths = np.diff(rows.indptr)
    p = p[lengths[p[:, 0]] < lengths[p[:, 1]]]  # (smaller, larger)
    implied = np.zeros(rows.shape[0], dtype=bool)
    implied[p[_subset_pairs(rows, p[:, 0], p[:, 1]), 1]] = True
    return ~implied


def _minimal(rows: sp.csr_matrix) -> np.ndarray:
    """Rows (distinct) that no other row is a subset of, by blocks of rows; all rows when that is too much work."""
    col_counts = np.diff(rows.tocsc().indptr).astype(np.int64)
    if int((col_counts**2).sum()) > FULL_CHECK_PAIRS:
        return np.ones(rows.shape[0], dtype=bool)
    lengths = np.diff(rows.indptr)
    implied = np.zeros(rows.shape[0], dtype=bool)
    rows_t = rows.T.tocsc()
    step = max(1, int(CHECK_BLOCK // max(1, rows.shape[0])))
    for start in range(0, rows.shape[0], step):
        common = (rows[start:start + step] @ rows_t).tocoo()  # (smaller candidate b, larger a)
        b = common.row + start
        sub = (common.data == lengths[b]) & (lengths[b] < lengths[common.col])
        implied[common.col[sub]] = True
    return ~implied


DENSE_SITES = 3000
"""Up to this many sites the domination test compares every pair of sites (dense ``n x n``); above, only pairs that
share a covered row and a neighbour or link."""


def _dominated(rows: sp.csr_matrix, links: sp.csr_matrix, base: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Sites to remove, each dominated by a site that stays or by the base stations (module docstring), and by whom.

    Returns:
        ``(drop, by)``: the mask of sites to remove and, for each, its dominator (-1: the base stations).
    """
    n = rows.shape[1]
    cov = rows.T.tocsr().astype(np.int32)
    cov_size = np.diff(cov.indptr)
    a = links.astype(np.int32).tocsr()
    deg = np.diff(a.indptr)
    common_cov = cov @ cov.T
    common_links = a @ a + a  # |N(j) & N(k)| + [k in N(j)]
    if n <= DENSE_SITES:
        dom = (common_cov.toarray() == cov_size[:, None]) & (common_links.toarray() == deg[:, None])
        dom &= ~base[:, None] | base[None, :]
        np.fill_diagonal(dom, False)
        pairs = np.nonzero(dom)
    else:
        c = common_cov.tocoo()
        covers = sp.csr_matrix((c.data == cov_size[c.row], (c.row, c.col)), shape=(n, n), dtype=bool)
        nl = common_links.tocoo()
        ok = (nl.data == deg[nl.row]) & (nl.row != nl.col) & (~base[nl.row] | base[nl.col])
        j, k = nl.row[ok], nl.col[ok]
        keep = np.asarray(covers[j, k]).ravel().astype(bool)
        pairs = (j[keep], k[keep])
    drop = (cov_size == 0) & (np.asarray(a @ (~base).astype(np.int32)).ravel() == 0)  # dominated by the bases
    order = np.argsort(pairs[0], kind="stable")
    j, k = pairs[0][order], pairs[1][order]
    by = np.full(n, -1, dtype=np.int64)
    bounds = np.searchsorted(j, np.arange(n + 1))
    for jj in np.unique(j).tolist():
        if drop[jj]:
            continue
        stays = k[bounds[jj]:bounds[jj + 1]]
        stays = stays[~drop[stays]]
        if len(stays):
            drop[jj] = True
            by[jj] = int(stays[0])
    return drop, by
