"""The radio's tables in an agent-assisted quiet stretch: what the radio medium's update builds, step after step.

A quiet stretch (:mod:`.stretch_kernels`) builds each step's neighbour table itself, as
:meth:`amronet.engine.radio.RadioMedium.update` builds it, with the same compiled functions on the same numbers:

* the pairs within the radio's reach (:func:`~amronet.engine.neighbours.search_kernel`): the *geometric* table, which
  the rings and the collision checks read;
* under the built-in path-loss law with walls or shadowing
  (:attr:`~amronet.engine.radio.RadioMedium.stretch_inputs`), the margin of every pair
  (:func:`~amronet.engine.links.path_loss_candidate_margins`, taking the previous step's margin of a pair whose two
  ends have not moved) and, as the table of links, the pairs whose margin is ``>= 0``
  (:func:`~amronet.engine.links.keep_entries`); otherwise every pair is a link;
* where the drop rule reads them (``link-quality``), the margins of the links: the path-loss law's, or by distance
  (:func:`~amronet.engine.links.distance_margins`, what :attr:`~amronet.engine.table.NeighbourTable.margin` gives).

Once nodes have failed (:attr:`Radio.silent`), their pairs are dropped from the links as the radio drops them
(:meth:`~amronet.engine.radio.RadioMedium.update`'s ``silent``): a link is a pair whose margin is ``>= 0`` and whose
two ends send; the geometric table keeps every pair (their bodies stay where they are).
The links are what the agents' tracking, their connection books, the drop rules and the repair read.

Under the path-loss law with walls or shadowing a pair may reach several ``r_c``, so nearly every pair is in the
geometric table; in a quiet stretch only the agents and the routers driving to their goals move. While few robots moved
(:data:`FEW_MOVED`) the tables are made of the last ones (:func:`moved_radio`): the entries between robots that stood
still copied, the moved robots' pairs made anew with the same operations; the same tables, entry for entry
(``tests/test_stretch_tables.py`` compares them with the tables built whole, :func:`rebuilt_radio`).
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numba import njit
from numba import uint64 as _u  # unsigned indices: no wraparound code, the copies vectorised

from amronet.engine.hearing import named_inputs
from amronet.engine.links import distance_margins, fresh_margin, keep_entries, open_radius, path_loss_candidate_margins
from amronet.engine.neighbours import search_kernel
from amronet.engine.shadowing import cell_value

__all__ = ["FEW_MOVED", "NO_MARGIN", "Radio", "margin_law", "moved_nodes", "moved_radio", "next_radio", "rebuilt_radio"]

NO_MARGIN = np.zeros(0)
"""The margins of a table whose margins nobody reads (a stand-in of their type)."""

FEW_MOVED = (1, 6)
"""``(p, q)``: :func:`next_radio` makes only the moved robots' pairs anew while at most ``p / q`` of the robots moved.

Measured on the office's tables under 4 dB shadowing (15 to 210 robots, nearly every pair within ``r``): with 3
robots moved a step costs 0.25 to 0.9 times the whole build, and the two cost the same at about 1/5 of them moved."""


class Radio(NamedTuple):
    """The radio's search radius ``r``, its inputs and this step's tables (every sensing and driving reach is in ``r``).

    Under the unit disk (and the path-loss law without walls and shadowing) the links are the geometric table.
    """

    r: float
    indptr: np.ndarray
    """The links' rows."""
    indices: np.ndarray
    dist: np.ndarray
    margin: np.ndarray
    """The links' margins where the drop rule reads them (else :data:`NO_MARGIN`)."""
    near_indptr: np.ndarray
    """The geometric table's rows: every pair within ``r``."""
    near_indices: np.ndarray
    near_dist: np.ndarray
    near_xy: np.ndarray
    """The positions the geometric table was built of."""
    near_margin: np.ndarray
    """Its pairs' margins under the path-loss law (else :data:`NO_MARGIN`)."""
    hearing: tuple
    """The radio's :class:`~amronet.engine.hearing.HearingInputs` as a plain tuple
    (:attr:`~amronet.engine.radio.RadioMedium.stretch_inputs`): with ``wall_db`` and ``clip`` 0, every pair is a
    link."""
    silent: np.ndarray
    """Which robots send nothing ``(N,)`` (failed ones; no entries: none), a link of which is none."""


@njit(cache=True, inline="always")
def margin_law(reads, hearing):  # pragma: no cover - numba
    """``(margins, law)``: whether the tables keep their links' margins, and how the rule reads them.

    ``reads``: the drop rule reads the links' margins; ``hearing``: the :attr:`Radio.hearing`. Where they are those of
    the links' lengths alone (no walls, no shadowing: :func:`~amronet.engine.links.distance_margins`) the tables keep
    none and ``law`` = ``(True, r_c, n10)`` tells the rule to take them of the lengths it reads
    (:func:`~.rule_kernels.best_distance_margins`); else ``margins`` is ``reads`` and ``law`` starts with ``False``.
    """
    h = named_inputs(hearing)
    by_distance = h.wall_db == 0.0 and h.clip == 0.0
    return reads and not by_distance, (by_distance, h.r_c, h.n10)


@njit(cache=True)
def next_radio(xy, radio, group, margins):  # pragma: no cover - numba
    """The radio after the robots moved to ``xy``: ``(ok, radio)`` (``ok`` false: a non-finite position, no table).

    ``radio``: a :class:`Radio` (a plain tuple); ``group``: zeros, one per robot; ``margins``: whether the links'
    margins are read (see the module docstring). Under the path-loss law with walls or shadowing, when a few robots
    moved (:data:`FEW_MOVED`), the tables are the last ones with the moved robots' pairs made anew
    (:func:`moved_radio`), else they are built whole (:func:`rebuilt_radio`): the same tables.
    """
    _, _, _, _, _, _, last_near_indices, _, last_near_xy, last_near_margin, hearing, _ = radio
    h = named_inputs(hearing)
    here = xy.copy()
    n = here.shape[0]
    if ((h.wall_db != 0.0 or h.clip != 0.0) and last_near_xy.shape[0] == n
            and last_near_margin.shape[0] == last_near_indices.shape[0]):
        moved = moved_nodes(here, last_near_xy)
        if moved.shape[0] * FEW_MOVED[1] <= n * FEW_MOVED[0]:
            return moved_radio(here, radio, moved)
    return rebuilt_radio(here, radio, group, margins)


@njit(cache=True)
def moved_nodes(xy, last_xy):  # pragma: no cover - numba
    """The robots, in ascending order, not standing exactly where they stood (``==``, as the margins' merge asks)."""
    n = xy.shape[0]
    out = np.empty(n, np.int64)
    k = 0
    for i in range(n):
        if not (xy[i, 0] == last_xy[i, 0] and xy[i, 1] == last_xy[i, 1]):
            out[k] = i
            k += 1
    return out[:k].copy()


@njit(cache=True)
def rebuilt_radio(here, radio, group, margins):  # pragma: no cover - numba
    """:func:`next_radio`'s tables built whole: every pair within ``r`` searched, ``here`` a copy of the positions."""
    (r, _, _, _, last_margin, last_near_indptr, last_near_indices, _, last_near_xy, last_near_margin, hearing,
     silent) = radio
    h = named_inputs(hearing)
    ok, near_indptr, near_indices, near_dist = search_kernel(here, r, group, np.int64(1))
    if not ok:
        return False, radio
    laws = h.wall_db != 0.0 or h.clip != 0.0
    if not laws and not silent.shape[0]:  # every pair is a link, its margin that of its length
        margin = distance_margins(near_dist, h.r_c, h.n10) if margins else last_margin
        return True, (r, near_indptr, near_indices, near_dist, margin, near_indptr, near_indices, near_dist, here,
                      last_near_margin, hearing, silent)
    # (the pairs of the last table whose two ends stand still keep their margins: the same numbers)
    near_margin = path_loss_candidate_margins(here, near_indptr, near_indices, near_dist, last_near_xy,
                                              last_near_indptr, last_near_indices, last_near_margin,
                                              hearing) if laws else last_near_margin
    keep = near_margin >= 0.0 if laws else np.ones(near_dist.shape[0], np.bool_)
    if silent.shape[0]:  # (as RadioMedium._links: neither end silent)
        for i in range(near_indptr.shape[0] - 1):
            for e in range(near_indptr[i], near_indptr[i + 1]):
                if silent[i] or silent[near_indices[e]]:
                    keep[e] = False
    if keep.all():  # every pair is a link (the stand-ins passed on: a global array would be read-only, of another type)
        margin = near_margin if laws else (distance_margins(near_dist, h.r_c, h.n10) if margins else last_margin)
        return True, (r, near_indptr, near_indices, near_dist, margin, near_indptr, near_indices, near_dist, here,
                      near_margin, hearing, silent)
    indptr, indices, dist, margin = keep_entries(near_indptr, near_indices, near_dist,
                                                 near_margin if laws else near_dist, keep)
    if not laws:  # the links' margins by their lengths
        margin = distance_margins(dist, h.r_c, h.n10) if margins else last_margin
    return True, (r, indptr, indices, dist, margin, near_indptr, near_indices, near_dist, here, near_margin, hearing,
                  silent)


@njit(cache=True)
def moved_radio(here, radio, moved):  # pragma: no cover - numba
    """:func:`next_radio`'s tables under the path-loss law with walls or shadowing, of the last ones: ``(ok, radio)``.

    ``moved``: the robots not standing where the last tables were built (:func:`moved_nodes`), whose positions
    ``here`` holds. A pair of two robots that stood still is in the new geometric table if it was in the last one, with
    the same length and margin (both are of the two positions alone): its entries are copied, row by row. The moved
    robots' pairs are made anew, as :func:`~amronet.engine.neighbours.search_kernel` finds and measures them (within
    ``r`` by ``dx * dx + dy * dy <= r * r``, their lengths the square roots of those sums) and as
    :func:`~amronet.engine.links.path_loss_candidate_margins` takes their margins (from the lower id,
    :func:`~amronet.engine.links.fresh_margin`), and merged into the rows in index order. The links are the entries
    whose margin is ``>= 0`` and whose two ends send, as :func:`rebuilt_radio` keeps them: the same tables.
    """
    (r, _, _, _, _, last_near_indptr, last_near_indices, last_near_dist, _, last_near_margin, hearing,
     silent) = radio
    n = here.shape[0]
    k = moved.shape[0]
    for q in range(k):  # (the search's answer to a non-finite position; the robots standing still were finite)
        if not (math.isfinite(here[moved[q], 0]) and math.isfinite(here[moved[q], 1])):
            return False, radio
    h = named_inputs(hearing)
    r_c, n10, wall_db, corr, clip = h.r_c, h.n10, h.wall_db, h.corr, h.clip
    values, x0, y0, cell = h.field
    w = h.walls
    blocked, jump, bits, ox, oy, res = w.blocked, w.clear, h.wall_bits, w.ox, w.oy, w.res
    law = (r_c, n10, wall_db, corr, clip, blocked.shape[1], ox, oy, res)
    mute = silent if silent.shape[0] else np.zeros(n, np.bool_)
    slot = np.full(n, -1, np.int64)  # a moved robot's place in moved
    for q in range(k):
        slot[moved[q]] = q
    # the moved robots' pairs: within r, their lengths and margins (a pair of two moved robots twice, the same)
    shade = np.zeros(n)
    radius = np.zeros(n)
    for i in range(n):
        if clip > 0.0:
            shade[i] = cell_value(values, x0, y0, cell, here[i, 0], here[i, 1])
        if wall_db > 0.0:
            radius[i] = open_radius(here[i, 0], here[i, 1], jump, ox, oy, res)
    r2 = r * r
    within = np.zeros((k, n), np.bool_)
    fresh_dist = np.empty((k, n))
    fresh = np.empty((k, n))
    for q in range(k):
        u = moved[q]
        xu = here[u, 0]
        yu = here[u, 1]
        for v in range(n):
            dx = here[v, 0] - xu
            dy = here[v, 1] - yu
            d2 = dx * dx + dy * dy
            if v == u or not d2 <= r2:
                continue
            d = math.sqrt(d2)
            a, b = (u, v) if u < v else (v, u)
            within[q, v] = True
            fresh_dist[q, v] = d
            fresh[q, v] = fresh_margin(d, (here[a, 0], here[a, 1], shade[a], radius[a]),
                                       (here[b, 0], here[b, 1], shade[b], radius[b]), law, bits, blocked, jump)
    # where each moved robot stands (or would) in each still robot's last row (rows are sorted by index)
    at = np.empty((n, k), np.int64)
    rows = np.empty(n + 1, np.int64)
    rows[0] = 0
    for i in range(n):
        qi = slot[i]
        c = 0
        if qi >= 0:
            for v in range(n):
                c += 1 if within[qi, v] else 0
        else:
            lo = last_near_indptr[i]
            hi = last_near_indptr[i + 1]
            c = hi - lo
            for q in range(k):
                u = moved[q]
                lo = _first_at_least(last_near_indices, lo, hi, u)
                at[i, q] = lo
                c += (1 if within[q, i] else 0) - (1 if lo < hi and last_near_indices[lo] == u else 0)
        rows[i + 1] = rows[i] + c
    # the rows: the last entries between robots that stood still, the moved robots' merged in by index; each row's
    # links as soon as it is written (the pairs whose margin is >= 0 and whose two ends send, as rebuilt_radio keeps)
    nnz = rows[n]
    near_indices = np.empty(nnz, last_near_indices.dtype)
    near_dist = np.empty(nnz)
    near_margin = np.empty(nnz)
    indptr = np.zeros(n + 1, np.int64)
    indices = np.empty(nnz, last_near_indices.dtype)
    dist = np.empty(nnz)
    margin = np.empty(nnz)
    f = 0
    for i in range(n):
        o = rows[i]
        qi = slot[i]
        if qi >= 0:
            for v in range(n):
                if within[qi, v]:
                    near_indices[o] = v
                    near_dist[o] = fresh_dist[qi, v]
                    near_margin[o] = fresh[qi, v]
                    o += 1
        else:
            _merge_row(i, o, moved, (within, fresh_dist, fresh, at), (last_near_indptr, last_near_indices,
                       last_near_dist, last_near_margin), (near_indices, near_dist, near_margin))
        if not mute[i]:  # (a few in a row: a branch seldom taken)
            for e in range(rows[i], rows[i + 1]):
                if near_margin[_u(e)] >= 0.0 and not mute[_u(near_indices[_u(e)])]:
                    indices[_u(f)] = near_indices[_u(e)]
                    dist[_u(f)] = near_dist[_u(e)]
                    margin[_u(f)] = near_margin[_u(e)]
                    f += 1
        indptr[i + 1] = f
    if f == nnz:  # every pair is a link (as rebuilt_radio passes them on)
        return True, (r, rows, near_indices, near_dist, near_margin, rows, near_indices, near_dist, here, near_margin,
                      hearing, silent)
    return True, (r, indptr, indices[:f].copy(), dist[:f].copy(), margin[:f].copy(), rows, near_indices, near_dist,
                  here, near_margin, hearing, silent)


@njit(cache=True, inline="always")
def _merge_row(i, o, moved, fresh_pairs, last, out):  # pragma: no cover - numba
    """Row ``i`` (a robot that stood still) of :func:`moved_radio`'s geometric table, written from ``o`` on.

    The last row's entries in blocks between the moved robots' places (``at[i]``), each moved robot's pair in its
    place where it is within ``r``. ``fresh_pairs``: ``(within, fresh_dist, fresh, at)``; ``last``: the last table's
    ``(indptr, indices, dist, margin)``; ``out``: the new ``(indices, dist, margin)``. The blocks are copied by loops
    on unsigned indices (not slices: see rule_kernels.rule_commit), which compile to plain copies.
    """
    within, fresh_dist, fresh, at = fresh_pairs
    last_indptr, last_indices, last_dist, last_margin = last
    near_indices, near_dist, near_margin = out
    k = moved.shape[0]
    s = last_indptr[i]
    hi = last_indptr[i + 1]
    for q in range(k + 1):
        stop = at[i, q] if q < k else hi
        for e in range(s, stop):
            near_indices[_u(o + e - s)] = last_indices[_u(e)]
            near_dist[_u(o + e - s)] = last_dist[_u(e)]
            near_margin[_u(o + e - s)] = last_margin[_u(e)]
        o += stop - s
        s = stop
        if q == k:
            break
        if s < hi and last_indices[s] == moved[q]:
            s += 1
        if within[q, i]:
            near_indices[o] = moved[q]
            near_dist[o] = fresh_dist[q, i]
            near_margin[o] = fresh[q, i]
            o += 1


@njit(cache=True, inline="always")
def _first_at_least(a, lo, hi, x):  # pragma: no cover - numba
    """The first place in ``a[lo:hi]`` (sorted) holding ``x`` or more (``hi``: none)."""
    while lo < hi:
        mid = (lo + hi) >> 1
        if a[mid] < x:
            lo = mid + 1
        else:
            hi = mid
    return lo
