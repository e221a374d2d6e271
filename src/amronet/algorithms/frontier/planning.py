"""Targets and the breadth-first search to the best of them (see the package's docstring).

A target is a traversable cell not yet visited with a seen uncovered cell (:data:`UNCOVERED`) or else a
frontier cell (:data:`FRONTIER`) within ``window`` cells; its score is its path length plus ``gap_weight``
times its distance to uncovered space. The numba kernels here serve both the public helpers
(:func:`target_kinds`, :func:`find_path`) and the agents' navigation kernel.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from amronet.algorithms.frontier.knowledge import KnowledgeGrid, _free, _offsets, _passable, _passable_mask

__all__ = ["FRONTIER", "UNCOVERED", "find_path", "gap_to_uncovered", "target_kinds"]

UNCOVERED = 1
"""Target kind: a seen, uncovered cell is near (going there releases a router)."""
FRONTIER = 2
"""Target kind: a frontier cell is near, and everything seen around it is covered."""


@njit(cache=True, inline="always")
def _box(ii, r, c, rad):  # pragma: no cover - numba
    rows = ii.shape[0] - 1
    cols = ii.shape[1] - 1
    r0 = max(0, r - rad)
    r1 = min(rows, r + rad + 1)
    c0 = max(0, c - rad)
    c1 = min(cols, c + rad + 1)
    return ii[r1, c1] - ii[r0, c1] - ii[r1, c0] + ii[r0, c0]


@njit(cache=True, inline="always")
def _is_frontier(score, seen, r, c):  # pragma: no cover - numba
    """A free cell with an unknown 4-neighbour."""
    rows, cols = seen.shape
    if not _free(score, seen, r, c):
        return False
    return ((r > 0 and not seen[r - 1, c]) or (r + 1 < rows and not seen[r + 1, c])
            or (c > 0 and not seen[r, c - 1]) or (c + 1 < cols and not seen[r, c + 1]))


@njit(cache=True)
def _integrals(score, seen, covered, fr_ii, us_ii):  # pragma: no cover - numba
    """Integral images (``ii[r, c]`` counts rows ``< r``, columns ``< c``) of frontier and seen uncovered cells.

    A frontier cell is a free cell with an unknown 4-neighbour. Row by row, through row views; a neighbour
    beyond the grid's edge is replaced by the cell itself (seen when it matters), which spares the bounds tests.
    """
    rows, cols = seen.shape
    for c in range(cols + 1):
        fr_ii[0, c] = 0
        us_ii[0, c] = 0
    for r in range(rows):
        s_row = seen[r]
        s_up = seen[r - 1 if r > 0 else r]
        s_down = seen[r + 1 if r + 1 < rows else r]
        sc_row = score[r]
        cv_row = covered[r]
        f_prev = fr_ii[r]
        u_prev = us_ii[r]
        f_cur = fr_ii[r + 1]
        u_cur = us_ii[r + 1]
        f_cur[0] = 0
        u_cur[0] = 0
        run_f = 0
        run_u = 0
        for c in range(cols):
            if s_row[c]:
                known4 = (s_up[c] and s_down[c] and s_row[c - 1 if c > 0 else c]
                          and s_row[c + 1 if c + 1 < cols else c])
                if sc_row[c] <= 0 and not known4:
                    run_f += 1
                if not cv_row[c]:
                    run_u += 1
            f_cur[c + 1] = f_prev[c + 1] + run_f
            u_cur[c + 1] = u_prev[c + 1] + run_u


@njit(cache=True, inline="always")
def _kind_of(trav, visited, fr_ii, us_ii, win, r, c):  # pragma: no cover - numba
    """Target kind of a cell (0: not a target) from the traversable mask and the integral images."""
    if visited[r, c] or not trav[r, c]:
        return 0
    if _box(us_ii, r, c, win) > 0:
        return 1
    if _box(fr_ii, r, c, win) > 0:
        return 2
    return 0


@njit(cache=True)
def _kind_direct(score, seen, rb, covered, visited, off_r, off_c, win, r, c):  # pragma: no cover - numba
    """Same as :func:`_kind_of` by direct look-ups (the per-step check of a goal)."""
    if visited[r, c] or not _passable(score, seen, rb, r, c, off_r, off_c):
        return 0
    rows, cols = seen.shape
    frontier = False
    for rr in range(max(0, r - win), min(rows, r + win + 1)):
        for cc in range(max(0, c - win), min(cols, c + win + 1)):
            if seen[rr, cc] and not covered[rr, cc]:
                return 1
            if not frontier and _is_frontier(score, seen, rr, cc):
                frontier = True
    return 2 if frontier else 0


@njit(cache=True)
def _all_kinds(score, seen, rb, covered, visited, off_r, off_c, win, trav, fr_ii, us_ii, out):  # pragma: no cover
    rows, cols = score.shape
    _integrals(score, seen, covered, fr_ii, us_ii)
    _passable_mask(score, seen, rb, off_r, off_c, trav)
    for r in range(rows):
        for c in range(cols):
            out[r, c] = _kind_of(trav, visited, fr_ii, us_ii, win, r, c)


@njit(cache=True, inline="always")
def _push(parent, depth, queue, tail, u, v, d):  # pragma: no cover - numba
    if parent[v] >= 0:
        return tail
    parent[v] = u
    depth[v] = d + 1
    queue[tail] = v
    return tail + 1


@njit(cache=True)
def _bfs(score, seen, visited, trav, fr_ii, us_ii, gap, win, sr, sc, escape, claims, claim_r2, openm, parent, depth,
         queue, path):  # pragma: no cover - numba
    """Breadth-first search from ``(sr, sc)`` for the best target; its path (start excluded) goes to ``path``.

    A path may enter traversable cells, and free cells within ``escape`` cells (Chebyshev) of the start; it
    steps diagonally only when both cells beside the step are open too. A target's score is its depth plus
    ``gap``; the best unclaimed target wins (the first of equal scores), else the best claimed one.

    Returns:
        ``(n, goal, kind)``: path length, flat goal cell (-1: none) and its target kind.
    """
    rows, cols = score.shape
    for r in range(rows):
        for c in range(cols):
            openm[r, c] = trav[r, c]
    for r in range(max(0, sr - escape), min(rows, sr + escape + 1)):
        for c in range(max(0, sc - escape), min(cols, sc + escape + 1)):
            if _free(score, seen, r, c):
                openm[r, c] = True
    parent[:] = -1
    start = sr * cols + sc
    parent[start] = start
    depth[start] = 0
    queue[0] = start
    head = 0
    tail = 1
    best = -1
    best_score = np.inf
    best_kind = 0
    backup = -1
    backup_score = np.inf
    backup_kind = 0
    while head < tail:
        u = queue[head]
        head += 1
        d = depth[u]
        if d >= best_score:
            break  # nothing farther out can score better
        r = u // cols
        c = u - r * cols
        kind = _kind_of(trav, visited, fr_ii, us_ii, win, r, c) if u != start else 0
        if kind:
            s = d + gap[r, c]
            claimed = False
            for j in range(claims.shape[0]):
                if claims[j, 0] < 0:
                    continue
                er = r - claims[j, 0]
                ec = c - claims[j, 1]
                if er * er + ec * ec <= claim_r2:
                    claimed = True
                    break
            if claimed:
                if s < backup_score:
                    backup, backup_score, backup_kind = u, s, kind
            elif s < best_score:
                best, best_score, best_kind = u, s, kind
        # neighbours in a fixed order: E, N, W, S, then NE, NW, SW, SE (no corner cutting)
        e = c + 1 < cols and openm[r, c + 1]
        n = r + 1 < rows and openm[r + 1, c]
        w = c > 0 and openm[r, c - 1]
        so = r > 0 and openm[r - 1, c]
        if e:
            tail = _push(parent, depth, queue, tail, u, u + 1, d)
        if n:
            tail = _push(parent, depth, queue, tail, u, u + cols, d)
        if w:
            tail = _push(parent, depth, queue, tail, u, u - 1, d)
        if so:
            tail = _push(parent, depth, queue, tail, u, u - cols, d)
        if n and e and openm[r + 1, c + 1]:
            tail = _push(parent, depth, queue, tail, u, u + cols + 1, d)
        if n and w and openm[r + 1, c - 1]:
            tail = _push(parent, depth, queue, tail, u, u + cols - 1, d)
        if so and w and openm[r - 1, c - 1]:
            tail = _push(parent, depth, queue, tail, u, u - cols - 1, d)
        if so and e and openm[r - 1, c + 1]:
            tail = _push(parent, depth, queue, tail, u, u - cols + 1, d)
    if best < 0:
        best, best_kind = backup, backup_kind
    if best < 0:
        return 0, -1, 0
    n_path = depth[best]
    v = best
    for q in range(n_path - 1, -1, -1):
        path[q] = v
        v = parent[v]
    return n_path, best, best_kind


@njit(cache=True)
def _nearest_uncovered(seen, covered, r, c, win, x, y, ox, oy, res):  # pragma: no cover - numba
    """The seen, uncovered cell within ``win`` cells of ``(r, c)`` nearest to the point ``(x, y)`` (-1: none)."""
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


@njit(cache=True)
def _edt(covered, out):  # pragma: no cover - numba
    """Exact Euclidean distance transform (Meijster et al. 2000) of ``covered`` into ``out``.

    ``out`` gets the distance from every cell to the nearest cell where ``covered`` is ``False``: the square root
    of an exact integer, computed in integer arithmetic, so the values equal SciPy's ``distance_transform_edt``.
    There must be at least one uncovered cell.
    """
    rows, cols = covered.shape
    inf = rows + cols
    g = np.empty((rows, cols), dtype=np.int64)
    for c in range(cols):  # phase 1: distance to the nearest uncovered cell in the same column (row by row)
        g[0, c] = inf if covered[0, c] else 0
    for r in range(1, rows):
        for c in range(cols):
            g[r, c] = g[r - 1, c] + 1 if covered[r, c] else 0
    for r in range(rows - 2, -1, -1):
        for c in range(cols):
            if g[r + 1, c] < g[r, c]:
                g[r, c] = g[r + 1, c] + 1
    f = np.empty(cols, dtype=np.int64)  # g^2 along the row
    s = np.empty(cols, dtype=np.int64)
    t = np.empty(cols, dtype=np.int64)
    for r in range(rows):  # phase 2: lower envelope of the parabolas (x - i)^2 + g[r, i]^2 along the row
        for c in range(cols):
            f[c] = g[r, c] * g[r, c]
        q = 0
        s[0] = 0
        t[0] = 0
        for u in range(1, cols):
            while q >= 0:
                i = s[q]
                a = t[q] - i
                b = t[q] - u
                if a * a + f[i] <= b * b + f[u]:
                    break
                q -= 1
            if q < 0:
                q = 0
                s[0] = u
            else:
                i = s[q]
                w = 1 + (u * u - i * i + f[u] - f[i]) // (2 * (u - i))
                if w < cols:
                    q += 1
                    s[q] = u
                    t[q] = w
        for u in range(cols - 1, -1, -1):
            i = s[q]
            out[r, u] = math.sqrt(float((u - i) * (u - i) + f[i]))
            if u == t[q]:
                q -= 1


def gap_to_uncovered(covered: np.ndarray) -> np.ndarray:
    """Distance in cells from every cell's centre to the nearest uncovered cell's centre (0 where uncovered).

    Where nothing is uncovered it is the constant ``rows + cols``: targets then rank by path length alone.
    The same values as ``scipy.ndimage.distance_transform_edt(covered)``, computed without its overhead.
    """
    covered = np.asarray(covered, dtype=bool)
    if covered.all():
        return np.full(covered.shape, float(sum(covered.shape)))
    out = np.empty(covered.shape)
    _edt(covered, out)
    return out


def _integral_buffers(shape: tuple[int, int]) -> tuple[np.ndarray, np.ndarray]:
    """Scratch integral images of frontier and seen uncovered cells for :func:`_integrals`."""
    rows, cols = shape
    return np.zeros((rows + 1, cols + 1), dtype=np.int32), np.zeros((rows + 1, cols + 1), dtype=np.int32)


def _search_buffers(n_cells: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Scratch ``(parent, depth, queue)`` of :func:`_bfs` on a grid of ``n_cells`` cells."""
    return np.zeros(n_cells, dtype=np.int64), np.zeros(n_cells, dtype=np.int64), np.zeros(n_cells, dtype=np.int64)


def _mask(grid: KnowledgeGrid, mask: np.ndarray | None) -> np.ndarray:
    if mask is None:
        return np.zeros(grid.shape, dtype=np.bool_)
    mask = np.asarray(mask, dtype=np.bool_)
    if mask.shape != grid.shape:
        raise ValueError(f"mask of shape {mask.shape} for a grid of shape {grid.shape}")
    return mask


def target_kinds(grid: KnowledgeGrid, covered: np.ndarray, visited: np.ndarray | None = None,
                 robots: np.ndarray | None = None, *, clearance: float = 0.3, window: int = 2) -> np.ndarray:
    """Target kind of every cell: 0 (none), :data:`UNCOVERED` or :data:`FRONTIER` (see the package's docstring).

    Args:
        grid: The knowledge grid.
        covered: Covered cells (:meth:`KnowledgeGrid.covered_by` of the deployed nodes).
        visited: Cells that are no longer targets; none by default.
        robots: Cells next to deployed nodes, not traversable (:meth:`KnowledgeGrid.covered_by` of the nodes
            with the clearance as radius); none by default.
        clearance: Inflation radius of occupied cells in metres.
        window: Targets have a seen uncovered cell or a frontier cell within this many cells (a square).

    Returns:
        ``(rows, cols)`` int8 array of target kinds.
    """
    off_r, off_c = _offsets(clearance, grid.resolution)
    out = np.zeros(grid.shape, dtype=np.int8)
    _all_kinds(grid.score, grid.seen, _mask(grid, robots), _mask(grid, covered), _mask(grid, visited), off_r,
               off_c, int(window), np.zeros(grid.shape, dtype=np.bool_), *_integral_buffers(grid.shape), out)
    return out


def find_path(grid: KnowledgeGrid, start: tuple[int, int], covered: np.ndarray,
              visited: np.ndarray | None = None, robots: np.ndarray | None = None, claims: np.ndarray | None = None,
              *, clearance: float = 0.3, window: int = 2, claim_radius: float = 0.0, escape: int = 1,
              gap_weight: float = 1.5) -> tuple[np.ndarray, int]:
    """Plan as an agent does: the shortest path from ``start`` to the best target (see the package's docstring).

    Args:
        grid: The knowledge grid.
        start: ``(row, col)`` of the agent's cell.
        covered: Covered cells (:meth:`KnowledgeGrid.covered_by` of the deployed nodes).
        visited: Cells that are no longer targets; none by default.
        robots: Cells next to deployed nodes, not traversable; none by default.
        claims: Goal cells ``(K, 2)`` of the other agents (rows of -1 are ignored).
        clearance: Inflation radius of occupied cells in metres.
        window: See :func:`target_kinds`.
        claim_radius: Targets within this many metres of a claim are left to its agent while others exist.
        escape: Near the start (this many cells, Chebyshev) free cells that are not traversable may be crossed.
        gap_weight: Weight of a target's distance to uncovered space in its score.

    Returns:
        ``(cells, kind)``: the path's cells ``(n, 2)`` as ``(row, col)``, start excluded, goal last (empty when
        no target is reachable), and the goal's target kind (0 when none).
    """
    rows, cols = grid.shape
    covered = _mask(grid, covered)
    claims = np.full((0, 2), -1, dtype=np.int64) if claims is None else np.asarray(claims, dtype=np.int64)
    off_r, off_c = _offsets(clearance, grid.resolution)
    fr_ii, us_ii = _integral_buffers(grid.shape)
    _integrals(grid.score, grid.seen, covered, fr_ii, us_ii)
    trav = np.zeros(grid.shape, dtype=np.bool_)
    _passable_mask(grid.score, grid.seen, _mask(grid, robots), off_r, off_c, trav)
    n_cells = rows * cols
    path = np.zeros(n_cells, dtype=np.int64)
    n, _, kind = _bfs(grid.score, grid.seen, _mask(grid, visited), trav, fr_ii, us_ii,
                      gap_weight * gap_to_uncovered(covered), int(window), int(start[0]), int(start[1]), int(escape),
                      claims.reshape(-1, 2), float((claim_radius / grid.resolution) ** 2),
                      np.zeros(grid.shape, dtype=np.bool_), *_search_buffers(n_cells), path)
    cells = path[:n]
    return np.stack([cells // cols, cells % cols], axis=1), int(kind)
