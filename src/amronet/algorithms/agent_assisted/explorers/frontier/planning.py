"""Targets and the breadth-first search to the best of them (see the package's docstring).

A target is a traversable cell not yet visited with a seen uncovered cell (:data:`UNCOVERED`) or else a
frontier cell (:data:`FRONTIER`) within ``window`` cells; its score is its path length plus ``gap_weight``
times its distance to uncovered space. The agents' navigation kernel
(:func:`~amronet.algorithms.agent_assisted.explorers.frontier.navigation.navigate`) keeps the window counts up to date
with
:func:`update_window_counts`, checks its goal with :func:`kind_at` and plans with :func:`search_target`.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numba import njit

from amronet.algorithms.agent_assisted.explorers.frontier.knowledge import is_free, passable

__all__ = [
    "FRONTIER",
    "UNCOVERED",
    "Claims",
    "Targets",
    "kind_at",
    "nearest_uncovered",
    "search_buffers",
    "search_target",
    "update_window_counts",
    "window_buffers",
]

UNCOVERED = 1
"""Target kind: a seen, uncovered cell is near (going there releases a router)."""
FRONTIER = 2
"""Target kind: a frontier cell is near, and everything seen around it is covered."""


class Targets(NamedTuple):
    """Which cells are targets and how they score, as :func:`search_target` reads them (a plain tuple there)."""

    visited: np.ndarray
    """Cells that are no longer targets ``(rows, cols)``."""
    counts: np.ndarray
    """Window counts of the frontier and seen uncovered cells (:func:`update_window_counts`)."""
    gap: np.ndarray
    """Per cell, what its distance to uncovered space adds to a target's score ``(rows, cols)``."""
    win: int
    """Window half-width in cells."""
    least_gap: float
    """``max(0, gap.min())``: no target's score is below its depth plus this."""


class Claims(NamedTuple):
    """The other agents' goals, whose targets are left to them, as :func:`search_target` reads them."""

    goals: np.ndarray
    """``(row, col)`` of the other agents' goals ``(K, 2)``; rows of -1 are ignored."""
    r2: float
    """Squared radius in cells around a goal within which targets are left to its agent."""


@njit(cache=True, inline="always")
def _is_frontier(score, seen, r, c):  # pragma: no cover - numba
    """A free cell with an unknown 4-neighbour."""
    rows, cols = seen.shape
    if not is_free(score, seen, r, c):
        return False
    return ((r > 0 and not seen[r - 1, c]) or (r + 1 < rows and not seen[r + 1, c])
            or (c > 0 and not seen[r, c - 1]) or (c + 1 < cols and not seen[r, c + 1]))


@njit(cache=True)
def update_window_counts(score, seen, covered, win, changed_fr, changed_us, marks,
                         counts):  # pragma: no cover - numba
    """Bring the window counts of frontier and seen uncovered cells up to date after some rows changed (compiled).

    ``marks[0]`` flags the frontier cells (free, with an unknown 4-neighbour), ``marks[1]`` the seen uncovered
    cells; ``counts[k, r, j]`` sums ``marks[k]`` over the rows within ``win`` of row ``r`` and the columns
    ``< j``, so that a window's count is the difference of two entries. Only the marks and counts that depend
    on the flagged rows are computed again (every row flagged: all of them).

    Args:
        score: Evidence counts ``(rows, cols)``.
        seen: Seen cells ``(rows, cols)``.
        covered: Covered cells ``(rows, cols)``.
        win: Window half-width in cells.
        changed_fr: Rows whose ``score`` or ``seen`` changed ``(rows,)``.
        changed_us: Rows whose ``seen`` or ``covered`` changed ``(rows,)``.
        marks: ``(2, rows, cols)`` int32, updated in place (:func:`window_buffers`).
        counts: ``(2, rows, cols + 1)`` int32, updated in place.
    """
    rows, cols = seen.shape
    mark_fr = np.zeros(rows, dtype=np.bool_)
    count_fr = np.zeros(rows, dtype=np.bool_)
    count_us = np.zeros(rows, dtype=np.bool_)
    for r in range(rows):
        # a frontier mark depends on the rows beside it, a count on the marks within ``win`` rows
        for rr in range(max(0, r - 1), min(rows, r + 2)):
            if changed_fr[rr]:
                mark_fr[r] = True
        if mark_fr[r]:
            for rr in range(max(0, r - win), min(rows, r + win + 1)):
                count_fr[rr] = True
        if changed_us[r]:
            for rr in range(max(0, r - win), min(rows, r + win + 1)):
                count_us[rr] = True
    for r in range(rows):
        if mark_fr[r]:
            _frontier_row(score, seen, r, marks[0, r])
        if changed_us[r]:
            s_row = seen[r]
            cv_row = covered[r]
            m_us = marks[1, r]
            for c in range(cols):
                m_us[c] = s_row[c] & ~cv_row[c]
    col = np.empty(cols, dtype=np.int32)
    for k in range(2):
        stale = count_fr if k == 0 else count_us
        r = 0
        while r < rows:  # a run of stale rows: a window sliding down the columns
            if not stale[r]:
                r += 1
                continue
            col[:] = 0
            for rr in range(max(0, r - win - 1), min(rows, r + win)):  # one row is taken off below
                _add_row(col, marks[k, rr], 1)
            while r < rows and stale[r]:
                if r + win < rows:
                    _add_row(col, marks[k, r + win], 1)
                if r - win - 1 >= 0:
                    _add_row(col, marks[k, r - win - 1], -1)
                out = counts[k, r]
                out[0] = 0
                run = 0
                for c in range(cols):
                    run += col[c]
                    out[c + 1] = run
                r += 1


@njit(cache=True, inline="always")
def _add_row(col, row, sign):  # pragma: no cover - numba
    for c in range(col.shape[0]):
        col[c] += sign * row[c]


@njit(cache=True)
def _frontier_row(score, seen, r, out):  # pragma: no cover - numba
    """``out[c]``: cell ``(r, c)`` is free with an unknown 4-neighbour (:func:`_is_frontier`), as 0 or 1."""
    rows, cols = seen.shape
    s_row = seen[r]
    s_up = seen[r - 1 if r > 0 else r]  # a neighbour beyond the edge: the cell itself (seen when it matters)
    s_down = seen[r + 1 if r + 1 < rows else r]
    sc_row = score[r]
    out[0] = s_row[0] and sc_row[0] <= 0 and not (s_up[0] and s_down[0] and s_row[min(1, cols - 1)])
    for c in range(1, cols - 1):
        out[c] = s_row[c] & (sc_row[c] <= 0) & ~(s_up[c] & s_down[c] & s_row[c - 1] & s_row[c + 1])
    if cols > 1:
        c = cols - 1
        out[c] = s_row[c] and sc_row[c] <= 0 and not (s_up[c] and s_down[c] and s_row[c - 1])


@njit(cache=True, inline="always")
def _in_window(counts, k, r, c, win):  # pragma: no cover - numba
    """How many cells of ``marks[k]`` (:func:`update_window_counts`) lie within ``win`` cells of ``(r, c)``."""
    cols = counts.shape[2] - 1
    return counts[k, r, min(cols, c + win + 1)] - counts[k, r, max(0, c - win)]


@njit(cache=True, inline="always")
def _kind_of(traversable, visited, counts, win, r, c):  # pragma: no cover - numba
    """Target kind of a cell (0: not a target) from whether it is traversable and the window counts."""
    if visited[r, c] or not traversable:
        return 0
    if _in_window(counts, 1, r, c, win) > 0:
        return UNCOVERED
    if _in_window(counts, 0, r, c, win) > 0:
        return FRONTIER
    return 0


@njit(cache=True)
def kind_at(score, seen, rb, covered, visited, off_r, off_c, win, r, c):  # pragma: no cover - numba
    """Target kind of cell ``(r, c)`` by direct look-ups: the per-step check of a goal (compiled).

    The same kind as the search gives the cell from its traversable mask and window counts.

    Args:
        score: Evidence counts ``(rows, cols)``.
        seen: Seen cells ``(rows, cols)``.
        rb: Cells next to known robots ``(rows, cols)``.
        covered: Covered cells ``(rows, cols)``.
        visited: Cells that are no longer targets ``(rows, cols)``.
        off_r: Row offsets of the cells within the clearance
            (:func:`~amronet.algorithms.agent_assisted.explorers.frontier.knowledge.clearance_offsets`).
        off_c: Their column offsets.
        win: Window half-width in cells.
        r: Row of the cell.
        c: Column of the cell.

    Returns:
        0 (not a target), :data:`UNCOVERED` or :data:`FRONTIER`.
    """
    if visited[r, c] or not passable(score, seen, rb, r, c, off_r, off_c):
        return 0
    rows, cols = seen.shape
    frontier = False
    for rr in range(max(0, r - win), min(rows, r + win + 1)):
        for cc in range(max(0, c - win), min(cols, c + win + 1)):
            if seen[rr, cc] and not covered[rr, cc]:
                return UNCOVERED
            if not frontier and _is_frontier(score, seen, rr, cc):
                frontier = True
    return FRONTIER if frontier else 0


@njit(cache=True, inline="always")
def _push(parent, depth, queue, tail, u, v, d):  # pragma: no cover - numba
    if parent[v] >= 0:
        return tail
    parent[v] = u
    depth[v] = d + 1
    queue[tail] = v
    return tail + 1


@njit(cache=True)
def search_target(score, seen, trav, targets, claims, sr, sc, escape, search, path):  # pragma: no cover - numba
    """Breadth-first search from ``(sr, sc)`` for the best target; its path (start excluded) goes to ``path``.

    A path may enter traversable cells, and free cells within ``escape`` cells (Chebyshev) of the start; it
    steps diagonally only when both cells beside the step are open too. A target's score is its depth plus
    ``gap``; the best unclaimed target wins (the first of equal scores), else the best claimed one (compiled).

    Args:
        score: Evidence counts ``(rows, cols)``.
        seen: Seen cells ``(rows, cols)``.
        trav: Traversable cells ``(rows, cols)``; the search opens the free cells near the start in it, and
            closes them again on return.
        targets: The targets (:class:`Targets`, as a plain tuple).
        claims: The other agents' goals (:class:`Claims`, as a plain tuple).
        sr: Row of the start.
        sc: Column of the start.
        escape: Chebyshev radius in cells around the start within which free cells may be crossed.
        search: Scratch parent, depth and queue of every cell (:func:`search_buffers`); the parents must be -1
            on entry, and are again on return.
        path: Gets the flat cells of the path, start excluded, goal last.

    Returns:
        ``(n, goal, kind)``: path length, flat goal cell (-1: none) and its target kind; ``(0, -1, 0)`` at once,
        nothing searched, when no cell is marked in ``counts`` (an agent with nothing left to explore replans often).
    """
    visited, counts, gap, win, least_gap = targets
    goals, claim_r2 = claims
    rows, cols = score.shape
    if not (counts[:, :, cols] != 0).any():  # no cell marked (a row's last count is its total): no target anywhere
        return 0, -1, 0
    parent = search[0]
    depth = search[1]
    queue = search[2]
    r0 = max(0, sr - escape)
    r1 = min(rows, sr + escape + 1)
    c0 = max(0, sc - escape)
    c1 = min(cols, sc + escape + 1)
    saved = np.empty((r1 - r0, c1 - c0), dtype=np.bool_)  # the traversable cells near the start
    for r in range(r0, r1):
        for c in range(c0, c1):
            saved[r - r0, c - c0] = trav[r, c]
            if is_free(score, seen, r, c):
                trav[r, c] = True
    start = sr * cols + sc
    parent[start] = start
    depth[start] = 0
    queue[0] = start
    head = 0
    tail = 1
    best = -1
    best_score = np.inf
    floor = 0.0  # once a target is found: no score below depth + least_gap, so none beats it farther out
    best_kind = 0
    backup = -1
    backup_score = np.inf
    backup_kind = 0
    while head < tail:
        u = queue[head]
        head += 1
        d = depth[u]
        if d + floor >= best_score:
            break  # nothing farther out can score better
        r = u // cols
        c = u - r * cols
        kind = 0
        if u != start:
            near = r0 <= r < r1 and c0 <= c < c1
            kind = _kind_of(saved[r - r0, c - c0] if near else trav[r, c], visited, counts, win, r, c)
        if kind:
            s = d + gap[r, c]
            claimed = False
            for j in range(goals.shape[0]):
                if goals[j, 0] < 0:
                    continue
                er = r - goals[j, 0]
                ec = c - goals[j, 1]
                if er * er + ec * ec <= claim_r2:
                    claimed = True
                    break
            if claimed:
                if s < backup_score:
                    backup, backup_score, backup_kind = u, s, kind
            elif s < best_score:
                floor = least_gap
                best, best_score, best_kind = u, s, kind
        # neighbours in a fixed order: E, N, W, S, then NE, NW, SW, SE (no corner cutting)
        e = c + 1 < cols and trav[r, c + 1]
        n = r + 1 < rows and trav[r + 1, c]
        w = c > 0 and trav[r, c - 1]
        so = r > 0 and trav[r - 1, c]
        if e:
            tail = _push(parent, depth, queue, tail, u, u + 1, d)
        if n:
            tail = _push(parent, depth, queue, tail, u, u + cols, d)
        if w:
            tail = _push(parent, depth, queue, tail, u, u - 1, d)
        if so:
            tail = _push(parent, depth, queue, tail, u, u - cols, d)
        if n and e and trav[r + 1, c + 1]:
            tail = _push(parent, depth, queue, tail, u, u + cols + 1, d)
        if n and w and trav[r + 1, c - 1]:
            tail = _push(parent, depth, queue, tail, u, u + cols - 1, d)
        if so and w and trav[r - 1, c - 1]:
            tail = _push(parent, depth, queue, tail, u, u - cols - 1, d)
        if so and e and trav[r - 1, c + 1]:
            tail = _push(parent, depth, queue, tail, u, u - cols + 1, d)
    if best < 0:
        best, best_kind = backup, backup_kind
    n_path = 0
    if best >= 0:
        n_path = depth[best]
        v = best
        for q in range(n_path - 1, -1, -1):
            path[q] = v
            v = parent[v]
    for q in range(tail):  # every cell with a parent was queued
        parent[queue[q]] = -1
    for r in range(r0, r1):
        for c in range(c0, c1):
            trav[r, c] = saved[r - r0, c - c0]
    return n_path, best, best_kind


@njit(cache=True)
def nearest_uncovered(seen, covered, r, c, win, x, y, ox, oy, res):  # pragma: no cover - numba
    """The seen, uncovered cell within ``win`` cells of ``(r, c)`` nearest to the point ``(x, y)`` (compiled).

    Args:
        seen: Seen cells ``(rows, cols)``.
        covered: Covered cells ``(rows, cols)``.
        r: Row of the window's centre.
        c: Column of the window's centre.
        win: Window half-width in cells.
        x: World x of the point.
        y: World y of the point.
        ox: World x of the grid's lower-left corner.
        oy: World y of the grid's lower-left corner.
        res: Cell size in metres.

    Returns:
        The flat cell, -1 when there is none.
    """
    rows, cols = seen.shape
    best = -1
    best_d = np.inf
    for rr in range(max(0, r - win), min(rows, r + win + 1)):
        for cc in range(max(0, c - win), min(cols, c + win + 1)):
            if seen[rr, cc] and not covered[rr, cc]:
                d = (ox + (cc + 0.5) * res - x) ** 2 + (oy + (rr + 0.5) * res - y) ** 2
                if d < best_d:
                    best_d = d
                    best = rr * cols + cc
    return best


def window_buffers(shape: tuple[int, int]) -> tuple[np.ndarray, np.ndarray]:
    """Scratch ``(marks, counts)`` of :func:`update_window_counts` for a grid of ``shape`` ``(rows, cols)``."""
    rows, cols = shape
    return np.zeros((2, rows, cols), dtype=np.int32), np.zeros((2, rows, cols + 1), dtype=np.int32)


def search_buffers(n_cells: int) -> np.ndarray:
    """Scratch parent (all -1), depth and queue ``(3, n_cells)`` of :func:`search_target` on ``n_cells`` cells."""
    search = np.zeros((3, n_cells), dtype=np.int64)
    search[0] = -1
    return search
