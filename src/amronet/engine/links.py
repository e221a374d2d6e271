"""From candidate pairs to links: the margin of every candidate, which links a step keeps, and packet loss.

The radio medium (:mod:`amronet.engine.radio`) searches the pairs within its reach (the *candidates*,
:mod:`amronet.engine.neighbours`), asks the model's margin kernel (:mod:`amronet.engine.hearing`) for the margin of
each (:func:`candidate_margins`, once per pair and mirrored) and keeps those at or above the threshold
(:func:`keep_entries`); with packet loss a link also drops out with probability one minus its delivery ratio
(:func:`losses`).

:func:`candidate_margins` calls ``model_margin``, here the path-loss law's;
:func:`amronet.engine.margin_kernels.margin_kernels` compiles copies of it that call another model's.
"""

from __future__ import annotations

import numpy as np
from numba import njit
from numba import uint64 as _u  # unsigned indices: numba then skips its negative-index wraparound code

from amronet.engine.hearing import named_inputs, open_margin, path_loss_margin, wall_limit
from amronet.engine.propagation import delivery_ratio
from amronet.engine.shadowing import cell_value
from amronet.engine.wall_bits import box_clear_bits, count_walls_bits, count_walls_lines

__all__ = ["NO_PREVIOUS", "candidate_margins", "distance_margins", "fresh_margin", "keep_entries", "losses",
           "mirror", "open_pair", "open_radius", "path_loss_candidate_margins"]

model_margin = path_loss_margin
"""The margin kernel :func:`candidate_margins` calls (a model's own in the copies of
:mod:`amronet.engine.margin_kernels`)."""

NO_PREVIOUS = (np.zeros((0, 2)), np.zeros(1, np.int64), np.zeros(0, np.int32), np.zeros(0))
"""The previous table ``(xy, indptr, indices, margin)`` of :func:`candidate_margins` when there is none."""


@njit(cache=True)
def mirror(indptr, indices):  # pragma: no cover - numba
    """For every entry ``(i, j)`` of a symmetric CSR with sorted rows, the position of its entry ``(j, i)``.

    Visiting the rows in order, the entries ``(j, i)`` with ``i < j`` of row ``j`` come up in column order, so a
    cursor per row finds each one in constant time.
    """
    n = indptr.shape[0] - 1
    out = np.empty(indices.shape[0], np.int64)
    cursor = indptr[:-1].copy()
    for i in range(n):
        for e in range(indptr[i], indptr[i + 1]):
            j = indices[e]
            if j > i:
                f = cursor[j]
                cursor[j] = f + 1
                out[e] = f
                out[f] = e
    return out


@njit(cache=True)
def candidate_margins(xy, indptr, indices, dist, prev_xy, prev_indptr, prev_indices, prev_margin,
                      hearing):  # pragma: no cover - numba
    """Margin of every candidate link (CSR order), computed once per pair (walking from the lower id) and mirrored.

    ``hearing``: the radio's :class:`~amronet.engine.hearing.HearingInputs` as a plain tuple
    (:meth:`~amronet.engine.hearing.HearingInputs.plain`). A pair whose two ends stand exactly where they
    stood in the previous table (``prev_*``, :data:`NO_PREVIOUS` for none) and were a candidate there takes its
    margin from it: a margin depends on the two positions alone, so it is the same number.
    """
    h = named_inputs(hearing)
    out = np.empty(indices.shape[0])
    cursor = indptr[:-1].copy()  # see mirror
    n_prev = prev_xy.shape[0]
    shadowed = h.clip > 0.0
    # out of the loops: an array read out of a tuple in a loop costs two atomic reference counts each time
    values, x0, y0, cell = h.field
    for i in range(indptr.shape[0] - 1):
        xa = xy[i, 0]
        ya = xy[i, 1]
        still_i = i < n_prev and xa == prev_xy[i, 0] and ya == prev_xy[i, 1]
        sa = cell_value(values, x0, y0, cell, xa, ya) if shadowed else 0.0
        p = prev_indptr[i] if still_i else 0  # row i of the previous table, merged along this one (both sorted)
        p_end = prev_indptr[i + 1] if still_i else 0
        for e in range(indptr[i], indptr[i + 1]):
            j = indices[e]
            if j < i:
                continue
            xb = xy[j, 0]
            yb = xy[j, 1]
            f = -1
            if still_i and j < n_prev and xb == prev_xy[j, 0] and yb == prev_xy[j, 1]:
                while p < p_end and prev_indices[p] < j:
                    p += 1
                if p < p_end and prev_indices[p] == j:
                    f = p
            if f >= 0:
                m = prev_margin[f]
            else:
                sb = cell_value(values, x0, y0, cell, xb, yb) if shadowed else 0.0
                m = model_margin(xa, ya, xb, yb, dist[e], sa, sb, 0.0, h)
            out[e] = m
            f = cursor[j]
            cursor[j] = f + 1
            out[f] = m
    return out


@njit(cache=True, inline="always")
def open_radius(x, y, jump, ox, oy, res):  # pragma: no cover - numba
    """How far a segment from ``(x, y)`` reaches without meeting a wall cell: its cell's safe jump (-1 off the map).

    :func:`~amronet.engine.walls.wall_grid`'s safe jump holds from any point of the cell, with a relative margin of
    1e-6 (and a positive jump is more than half a cell), far above the rounding of the cell lookup and of a length.
    """
    u = (x - ox) / res
    v = (y - oy) / res
    if not (u >= 0.0 and v >= 0.0 and u < jump.shape[1] and v < jump.shape[0]):
        return -1.0
    return float(jump[int(v), int(u)])


@njit(cache=True, inline="always")
def open_pair(d, ra, rb):  # pragma: no cover - numba
    """Whether a segment ``d`` long whose ends have the open radii ``ra`` and ``rb`` (:func:`open_radius`) is clear.

    Every point of the segment is less than ``ra`` from one end or less than ``rb`` from the other when
    ``d < ra + rb`` (the two distances sum to ``d``), and the disk of an end's open radius holds no wall cell: the
    walk would visit free cells only and count 0 (its own answer, without the walk). A radius of -1 (an end off the
    map) leaves the other end's disk alone: ``d < max(ra, rb, ra + rb)``, which is ``d < ra + rb`` for radii
    ``>= 0`` (rounding is monotone).
    """
    return d < max(ra, rb, ra + rb)


@njit(cache=True)
def path_loss_candidate_margins(xy, indptr, indices, dist, prev_xy, prev_indptr, prev_indices, prev_margin,
                                hearing):  # pragma: no cover - numba
    """:func:`candidate_margins` of the path-loss law (:func:`~amronet.engine.hearing.path_loss_margin`), faster.

    The same numbers bit for bit, by the law's own pieces: the inputs read once, not per pair, and a link shorter
    than the sum of its two ends' open radii (:func:`open_radius`, :func:`open_pair`) crosses no wall (every cell
    the walk would visit is free), so neither the box test nor the walk is asked. Whether a node stands where it
    stood in the previous table is decided once per node, and indices are read unsigned (no wraparound code).
    """
    h = named_inputs(hearing)
    out = np.empty(indices.shape[0])
    cursor = indptr[:-1].copy()  # see mirror
    n = indptr.shape[0] - 1
    n_prev = prev_xy.shape[0]
    r_c, n10, wall_db, corr, clip = h.r_c, h.n10, h.wall_db, h.corr, h.clip
    shadowed = clip > 0.0
    walled = wall_db > 0.0
    values, x0, y0, cell = h.field
    w = h.walls
    blocked, jump, bits, ox, oy, res = w.blocked, w.clear, h.wall_bits, w.ox, w.oy, w.res
    cols = blocked.shape[1]
    radius = np.empty(n if walled else 0)
    if walled:
        for i in range(n):
            # off the map (-1): 0, which keeps open_pair's answer (d < ra + 0 is d < ra) with one addition
            radius[_u(i)] = max(open_radius(xy[_u(i), 0], xy[_u(i), 1], jump, ox, oy, res), 0.0)
    still = np.zeros(n, np.bool_)  # where the node stood in the previous table
    for i in range(min(n, n_prev)):
        still[_u(i)] = xy[_u(i), 0] == prev_xy[_u(i), 0] and xy[_u(i), 1] == prev_xy[_u(i), 1]
    for i in range(n):
        xa = xy[_u(i), 0]
        ya = xy[_u(i), 1]
        still_i = still[_u(i)]
        sa = cell_value(values, x0, y0, cell, xa, ya) if shadowed else 0.0
        ra = radius[_u(i)] if walled else 0.0
        p = prev_indptr[_u(i)] if still_i else 0  # row i of the previous table, merged along this one (both sorted)
        p_end = prev_indptr[_u(i + 1)] if still_i else 0
        for e in range(indptr[_u(i)], indptr[_u(i + 1)]):
            j = indices[_u(e)]
            if j < i:
                continue
            f = -1
            if still_i and still[_u(j)]:
                while p < p_end and prev_indices[_u(p)] < j:
                    p += 1
                if p < p_end and prev_indices[_u(p)] == j:
                    f = p
            if f >= 0:
                m = prev_margin[_u(f)]
            else:
                xb = xy[_u(j), 0]
                yb = xy[_u(j), 1]
                d = dist[_u(e)]
                sb = cell_value(values, x0, y0, cell, xb, yb) if shadowed else 0.0
                m = open_margin(d, sa, sb, r_c, n10, corr, clip)
                if walled and m >= 0.0 and not d < ra + radius[_u(j)] and not box_clear_bits(
                        bits, cols, ox, oy, res, xa, ya, xb, yb):
                    m -= wall_db * _walls(bits, blocked, jump, ox, oy, res, xa, ya, xb, yb, wall_limit(m, 0.0, wall_db))
            out[_u(e)] = m
            f = cursor[_u(j)]
            cursor[_u(j)] = f + 1
            out[_u(f)] = m
    return out


@njit(cache=True, inline="always")
def fresh_margin(d, end_a, end_b, law, bits, blocked, jump):  # pragma: no cover - numba
    """:func:`path_loss_candidate_margins`' margin of a fresh pair ``a -> b`` (``a`` the lower id), ``d`` long.

    The same operations as that loop's, which keeps them written out (through this call it measured a fifth slower).

    ``end_a``, ``end_b``: each end's ``(x, y, s, radius)``, its shadowing field value (0 without shadowing) and its
    cell's open radius (:func:`open_radius`; 0 without walls); ``law``: the radio's numbers
    ``(r_c, n10, wall_db, corr, clip, cols, ox, oy, res)`` and ``bits``, ``blocked``, ``jump`` its wall grids, as the
    caller read them, once (tuples of numbers: no cost in compiled code).
    """
    xa, ya, sa, ra = end_a
    xb, yb, sb, rb = end_b
    r_c, n10, wall_db, corr, clip, cols, ox, oy, res = law
    m = open_margin(d, sa, sb, r_c, n10, corr, clip)
    if wall_db > 0.0 and m >= 0.0 and not open_pair(d, ra, rb) and not box_clear_bits(bits, cols, ox, oy, res, xa,
                                                                                       ya, xb, yb):
        m -= wall_db * _walls(bits, blocked, jump, ox, oy, res, xa, ya, xb, yb, wall_limit(m, 0.0, wall_db))
    return m


@njit(cache=True, inline="always")
def _walls(bits, blocked, jump, ox, oy, res, xa, ya, xb, yb, limit):  # pragma: no cover - numba
    """:func:`~amronet.engine.wall_bits.count_walls_bits`, asking its line-by-line count first.

    The same count (where the lines do not decide, the walk asks them again and walks): most links then pass one
    array to a call, not three (each array passed costs two atomic reference counts, more than a short count).
    """
    k = count_walls_lines(bits, blocked.shape[1], ox, oy, res, xa, ya, xb, yb, limit)
    return k if k >= 0 else count_walls_bits(bits, blocked, jump, ox, oy, res, xa, ya, xb, yb, limit)


@njit(cache=True)
def keep_entries(indptr, indices, dist, margin, keep):  # pragma: no cover - numba
    """The CSR arrays ``(indptr, indices, dist, margin)`` of the entries in ``keep``.

    Every entry up to the last one kept is written at the output's cursor, which moves on only past a kept one (a
    dropped entry is overwritten by the next): no branch per entry, which a table dropping one link in five at
    random would mispredict.
    """
    n = indptr.shape[0] - 1
    m = 0
    for e in range(keep.shape[0]):
        m += 1 if keep[_u(e)] else 0
    stop = keep.shape[0]  # past the last entry kept: the cursor stays below m up to there
    while stop > 0 and not keep[_u(stop - 1)]:
        stop -= 1
    out_ptr = np.empty(n + 1, np.int64)
    out_idx = np.empty(m, indices.dtype)
    out_dist = np.empty(m)
    out_margin = np.empty(m)
    out_ptr[0] = 0
    k = 0
    for i in range(n):
        for e in range(indptr[_u(i)], min(indptr[_u(i + 1)], stop)):
            out_idx[_u(k)] = indices[_u(e)]
            out_dist[_u(k)] = dist[_u(e)]
            out_margin[_u(k)] = margin[_u(e)]
            k += 1 if keep[_u(e)] else 0
        out_ptr[_u(i + 1)] = k
    return out_ptr, out_idx, out_dist, out_margin


def losses(rng: np.random.Generator, indptr: np.ndarray, indices: np.ndarray, margin: np.ndarray) -> np.ndarray:
    """Which entries drop out this step: one draw from ``rng`` per link (pair), shared by its two entries."""
    rows = np.repeat(np.arange(len(indptr) - 1), np.diff(indptr))
    upper = np.flatnonzero(indices > rows)
    across = mirror(indptr, indices)
    lost = np.zeros(len(indices), dtype=bool)
    drop = rng.random(len(upper)) >= delivery_ratio(margin[upper])
    lost[upper] = drop
    lost[across[upper]] = drop
    return lost


@njit(cache=True)
def distance_margins(dist, r_c, n10):  # pragma: no cover - numba
    """The margins of links ``dist`` long by distance alone (the path-loss law without walls and shadowing).

    What :attr:`~amronet.engine.table.NeighbourTable.margin` gives a table without margins of its own, and what a
    compiled stretch under the unit disk computes of its tables, with the same function (NumPy's ``log10`` may
    differ from the C library's in the last bit where it has vector code of its own).
    """
    out = np.empty(dist.shape[0])
    for e in range(dist.shape[0]):
        out[e] = open_margin(dist[e], 0.0, 0.0, r_c, n10, 0.0, 0.0)
    return out

