"""A neighbour table kept from step to step through a skin (a Verlet list): the same table as a search, for less.

From one step to the next most robots move a few centimetres, and the unit-disk table at radius ``r`` changes by a
few links. A skin table searches once at ``r + skin`` (:func:`~amronet.engine.neighbour_search.candidate_rows`) and
remembers where every robot stood then; while no robot has moved more than :data:`HALF_SKIN` of the skin from there,
every pair within ``r`` now was within ``r + skin`` then (by the triangle inequality, with a margin of a tenth of
the skin for the roundings, which are relative and tiny), so the table at ``r`` is those candidates that pass the
search's own test (:func:`~amronet.engine.neighbour_search.filter_rows`): the same table bit for bit, one pass over
the candidates instead of the search's five. When a robot went farther the candidates are searched again from where
everybody stands.

A skin is worth it only when it lasts: a table whose candidates had to be searched again after fewer than
:data:`SHORTEST_LIFE` steps (robots fast for the radius) is given up for plain searches (:func:`skin_search`), as
is a skin that would not be reused (the caller says so).
"""

from __future__ import annotations

import numpy as np
from numba import njit

from amronet.engine.neighbour_search import candidate_rows, filter_rows, search_kernel

__all__ = ["HALF_SKIN", "SHORTEST_LIFE", "SKIN", "no_skin", "skin_search"]

SKIN = 0.25
"""The skin, as a fraction of the table's radius."""

HALF_SKIN = 0.45
"""Farthest a robot may have moved from where the candidates were searched, as a fraction of the skin (half of it,
less a margin for the roundings)."""

SHORTEST_LIFE = 2
"""Fewest steps a skin must serve before its candidates are searched again, or it is given up."""

_OFF = -1  # given up: plain searches
_NONE = 0  # no candidates yet


@njit(cache=True, inline="always")
def no_skin():  # pragma: no cover - numba
    """A skin table's state before its first search (see :func:`skin_search`)."""
    return (np.zeros(1, np.int64), np.empty(0, np.int32), np.empty((0, 2)), _NONE, 0,
            (np.empty((2, 0), np.int64), np.empty((2, 0), np.int32), np.empty((2, 0)), np.empty(0)), 0)


@njit(cache=True, inline="always")
def _moved_too_far(xy, where, limit):  # pragma: no cover - numba
    """Whether a robot is farther than ``limit`` from where it stood (or its position is not finite)."""
    lim2 = limit * limit
    for i in range(xy.shape[0]):
        dx = xy[i, 0] - where[i, 0]
        dy = xy[i, 1] - where[i, 1]
        if not dx * dx + dy * dy <= lim2:
            return True
    return False


@njit(cache=True, inline="always")
def _filter(xy, r, cand_indptr, cand_indices, buffers, flip):  # pragma: no cover - numba
    """:func:`~amronet.engine.neighbour_search.filter_rows` into the buffers ``flip``.

    The table of the call before lives in the others until the next call replaces it.
    """
    indptrs, indices, dists, sq = buffers
    return filter_rows(xy, r, cand_indptr, cand_indices, indptrs[flip], indices[flip], sq, dists[flip])


@njit(cache=True, inline="always")
def _buffers(n, size, buffers):  # pragma: no cover - numba
    """``buffers`` if they hold ``size`` candidates of ``n`` points, else new ones with room to spare."""
    indptrs, sq = buffers[0], buffers[3]  # (indices and dists: as long as sq)
    if indptrs.shape[1] == n + 1 and sq.shape[0] >= size:
        return buffers
    cap = size + size // 4 + 16
    return np.empty((2, n + 1), np.int64), np.empty((2, cap), np.int32), np.empty((2, cap)), np.empty(cap)


@njit(cache=True, inline="always")
def skin_search(xy, r, group, n_groups, skin, reuse):  # pragma: no cover - numba
    """:func:`~amronet.engine.neighbour_search.search_kernel`'s ``(ok, indptr, indices, dist)`` through a skin.

    ``skin``: the state (:func:`no_skin`, then what the last call returned); ``reuse``: whether the table will be
    asked for again (a skin is searched only then). Returns ``(ok, indptr, indices, dist, skin)``. The tables of two
    calls in a row are in two sets of buffers, the third in the first set again: a caller keeps a table only until
    the next call but one.
    """
    cand_indptr, cand_indices, where, mode, life, buffers, flip = skin
    width = SKIN * r
    if mode > 0 and not _moved_too_far(xy, where, HALF_SKIN * width):
        indptr, indices, dist = _filter(xy, r, cand_indptr, cand_indices, buffers, flip)
        return True, indptr, indices, dist, (cand_indptr, cand_indices, where, mode, life + 1, buffers, 1 - flip)
    if mode > 0 and life < SHORTEST_LIFE:
        mode = _OFF
    if mode == _OFF or not reuse:
        ok, indptr, indices, dist = search_kernel(xy, r, group, n_groups)
        return ok, indptr, indices, dist, (cand_indptr, cand_indices, where, mode, life, buffers, flip)
    ok, cand_indptr, cand_indices = candidate_rows(xy, r + width, group, n_groups)
    if not ok:
        return (False, np.zeros(1, np.int64), np.empty(0, np.int32), np.empty(0),
                (cand_indptr, cand_indices, where, mode, life, buffers, flip))
    buffers = _buffers(xy.shape[0], cand_indices.shape[0], buffers)
    indptr, indices, dist = _filter(xy, r, cand_indptr, cand_indices, buffers, flip)
    return True, indptr, indices, dist, (cand_indptr, cand_indices, xy.copy(), 1, 1, buffers, 1 - flip)
