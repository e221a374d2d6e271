"""Reference tracking, shared by the greedy deployment of routers (self-spreading) and of agents.

A robot keeps a *current reference*: a deployed node (base reference node or deployed router) within ``r_c``.
It keeps the same one while it stays in range and otherwise takes the nearest one it hears. From its row of
the neighbour table it also learns the nearest reference in range, and the nearest reference whose status
differs from its current reference's (the trigger of the triangular deployment).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numba import njit

from amronet.engine.radio import NeighbourTable
from amronet.errors import ScenarioError


def check_loss_band(loss_margin: float, r_c: float, step: float, who: str) -> float:
    """Check that the "about to lose" band is wider than one step and return ``(1 - loss_margin) r_c``.

    A robot that could cross the band ``[(1 - loss_margin) r_c, r_c]`` in one step might lose its last reference
    before noticing it is about to.

    Raises:
        ScenarioError: The band is too narrow (names ``algorithm.params.loss_margin``).
    """
    band = loss_margin * r_c
    if step >= band:
        raise ScenarioError(
            "algorithm.params.loss_margin",
            f"the 'about to lose' band ({band:.3g} m) must be wider than one {who} step ({step:.3g} m); "
            "raise loss_margin or lower sim.dt",
        )
    return r_c - band

__all__ = ["ReferenceView", "best_reference_margin", "check_loss_band", "track_references", "track_row",
           "track_state_rows"]


@dataclass(frozen=True)
class ReferenceView:
    """What each tracking robot knows about the references around it (arrays aligned with ``who``).

    Attributes:
        current: Current reference after this step's update, -1 if none is in range.
        nearest_distance: Distance to the nearest reference in range, ``inf`` if none.
        other: Nearest reference in range whose status differs from the current reference's, -1 if none.
        other_distance: Distance to ``other``, ``inf`` if none.
    """

    current: np.ndarray
    nearest_distance: np.ndarray
    other: np.ndarray
    other_distance: np.ndarray

    @property
    def has_reference(self) -> np.ndarray:
        """Robots that hear at least one reference."""
        return self.current >= 0


@njit(cache=True)
def _nearest_other(lo, hi, s_cur, is_reference, status, indices, dist):  # pragma: no cover - numba
    o = -1
    od = np.inf
    for e in range(lo, hi):
        j = indices[e]
        sj = status[j]
        if is_reference[j] and sj >= 0 and sj != s_cur and dist[e] < od:
            od = dist[e]
            o = j
    return o, od


@njit(cache=True)
def track_row(i, cur, is_reference, status, indptr, indices, dist, want_other):  # pragma: no cover - numba
    """Track one robot ``i`` whose current reference is ``cur``: ``(current, nearest_distance, other, other_d)``.

    One pass over the row; a second only when the current reference changed (rare in steady state).
    """
    lo = indptr[i]
    hi = indptr[i + 1]
    s_cur = status[cur] if cur >= 0 else -1
    still = False
    best = -1
    best_d = np.inf
    o = -1
    od = np.inf
    for e in range(lo, hi):
        j = indices[e]
        if not is_reference[j]:
            continue
        de = dist[e]
        if j == cur:
            still = True
        if de < best_d:
            best_d = de
            best = j
        if want_other:
            sj = status[j]
            if sj >= 0 and s_cur >= 0 and sj != s_cur and de < od:
                od = de
                o = j
    chosen = cur if still else best
    if want_other and chosen != cur:
        o = -1
        od = np.inf
        if chosen >= 0 and status[chosen] >= 0:
            o, od = _nearest_other(lo, hi, status[chosen], is_reference, status, indices, dist)
    return chosen, best_d, o, od


@njit(cache=True)
def track_state_rows(state, tracking_state, current, is_reference, status, indptr, indices, dist, want_other,
                     out):  # pragma: no cover - numba
    """:func:`track_row` for every robot ``i`` with ``state[i] == tracking_state``, in index order; how many.

    ``out``: ``(who, new_current, nearest_d, other)``. Robot ``i``'s current reference is ``current[i]``; the
    ``k``-th such robot goes into ``who[k]``, its new
    reference, nearest reference distance and reference of another status into ``new_current[k]``,
    ``nearest_d[k]`` and ``other[k]``. :func:`track_row`'s operations written out in the loop, bit for bit: numba
    counts the references of the arrays handed to a function at every call, and at N = 3 000 those counts cost
    as much as the tracking itself. Each row's links to references are listed first, without a branch, and
    :func:`track_row`'s tests run over that list alone, in the row's order: most links lead to robots that are not
    references, and a branch on each of them, often mispredicted, took a large part of the tracking's time.
    """
    who, new_current, nearest_d, other = out
    widest = 0
    for i in range(state.shape[0]):
        widest = max(widest, indptr[i + 1] - indptr[i])
    refs = np.empty(widest + 1, np.int64)  # a row's links to references, listed without a branch
    k = 0
    for i in range(state.shape[0]):
        if state[i] != tracking_state:
            continue
        cur = current[i]
        lo = indptr[i]
        hi = indptr[i + 1]
        s_cur = status[cur] if cur >= 0 else -1
        still = False
        best = -1
        best_d = np.inf
        o = -1
        od = np.inf
        n_refs = 0
        for e in range(lo, hi):
            refs[n_refs] = e
            n_refs += is_reference[indices[e]]
        for q in range(n_refs):
            e = refs[q]
            j = indices[e]
            de = dist[e]
            if j == cur:
                still = True
            if de < best_d:
                best_d = de
                best = j
            if want_other:
                sj = status[j]
                if sj >= 0 and s_cur >= 0 and sj != s_cur and de < od:
                    od = de
                    o = j
        chosen = cur if still else best
        if want_other and chosen != cur:
            o = -1
            if chosen >= 0 and status[chosen] >= 0:
                o, od = _nearest_other(lo, hi, status[chosen], is_reference, status, indices, dist)
        who[k] = i
        new_current[k] = chosen
        nearest_d[k] = best_d
        other[k] = o
        k += 1
    return k


@njit(cache=True)
def _track(who, current, is_reference, status, indptr, indices, dist, want_other,
           new_current, nearest_d, other, other_d):  # pragma: no cover - numba
    """:func:`track_row` for every robot of ``who``."""
    for m in range(who.shape[0]):
        new_current[m], nearest_d[m], other[m], other_d[m] = track_row(
            who[m], current[m], is_reference, status, indptr, indices, dist, want_other)


def track_references(
    table: NeighbourTable,
    who: np.ndarray,
    current: np.ndarray,
    is_reference: np.ndarray,
    status: np.ndarray,
    want_other: bool = True,
) -> ReferenceView:
    """Update the current references of the robots ``who`` from their rows of the neighbour table.

    Args:
        table: This step's neighbour table.
        who: Indices of the tracking robots ``(M,)``.
        current: Their current references before this step ``(M,)`` (-1: none).
        is_reference: Boolean mask over all nodes: which ones serve as references.
        status: Status of all nodes.
        want_other: Look for references of another status (skip when only one status exists).

    Returns:
        The updated view; ``current`` is a new array. Ties in distance go to the lower node id.
    """
    m = len(who)
    new_current = np.empty(m, dtype=np.int64)
    nearest_d = np.empty(m)
    other = np.empty(m, dtype=np.int64)
    other_d = np.empty(m)
    _track(np.asarray(who, dtype=np.int64), np.asarray(current, dtype=np.int64), is_reference,
           status, table.indptr, table.indices, table.dist, want_other, new_current, nearest_d, other, other_d)
    return ReferenceView(new_current, nearest_d, other, other_d)


@njit(cache=True)
def _best_margin(who, is_reference, indptr, indices, margin, out):  # pragma: no cover - numba
    for m in range(who.shape[0]):
        i = who[m]
        best = -np.inf
        for e in range(indptr[i], indptr[i + 1]):
            if is_reference[indices[e]] and margin[e] > best:
                best = margin[e]
        out[m] = best


def best_reference_margin(table: NeighbourTable, who: np.ndarray, is_reference: np.ndarray) -> np.ndarray:
    """The best link margin (dB over the usable threshold) from each robot of ``who`` to a reference it hears.

    What a robot's radio measures of its links, no positions: ``-inf`` for a robot that hears no reference.
    """
    out = np.empty(len(who))
    _best_margin(np.asarray(who, dtype=np.int64), np.asarray(is_reference, dtype=np.bool_), table.indptr,
                 table.indices, np.asarray(table.margin, dtype=np.float64), out)
    return out
