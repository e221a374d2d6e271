"""Frontier exploration for agents that release routers (Yamauchi-style, on a map shared by all agents).

The agents of a run build one coarse **knowledge grid** together from what they sense, and each drives along
a shortest path on it to the nearest place where going makes the covered area grow.

Knowledge grid
    A grid over the area's bounding box at ``resolution`` metres (0.25 by default); each cell is *unknown*
    (never crossed by a beam), *free* or *occupied*. Every step, every beam of every agent marks the cells it
    crosses before its reading as free and, when it reads less than the sonar's maximum range, the cell at the
    reading as occupied. Evidence is counted per cell (a hit adds :data:`HIT_GAIN`, a pass removes 1, clamped
    to ``[-FREE_FLOOR, OCCUPIED_CAP]``) and a cell is occupied while its count is positive: walls, hit again
    and again, stay occupied when a beam grazes them, and a robot in transit that was seen once is cleared
    again once beams pass where it stood. Readings that end on a robot the agents know of — another agent (the
    agents share their poses) or a deployed router or base node (the AMRoNet reports them) — mark no obstacle:
    robots move or are thin, and the sonar avoidance takes care of them.

Traversable cells
    Free cells with no occupied cell centre within ``clearance`` metres of their centre (the body inflated);
    near its own position an agent may also cross free cells that are not traversable, to get out of them.

Targets (what makes coverage grow)
    A deployed node covers the cells whose centre lies within ``(1 - cover_margin) r_c`` of it; the others
    are *uncovered*. Agents release a router when about to lose their last reference, so coverage grows where
    agents go beyond the covered area: a traversable, not yet visited cell is a

    * *primary* target when it is uncovered, or when it is a frontier cell (an unknown cell lies within
      ``frontier_window`` cells) with an unknown, uncovered cell within ``reach`` metres (the sonar's range
      by default): going there either releases a router or reveals uncovered space;
    * *secondary* target when it is a frontier cell only (what lies beyond may lead to uncovered space).

    A target an agent reached, or gave up on, is *visited* and is never a target again: an agent that reached
    an uncovered cell without releasing a router was close enough to a reference, and a frontier it stood on
    is as resolved as the sonar can resolve it.

Planning
    Each agent plans with a breadth-first search over traversable cells (8-connected, a diagonal step only
    when both cells beside it are traversable: no corner cutting; neighbours in a fixed order, so ties break
    deterministically) from its own cell to the nearest primary target that no other agent has claimed (none
    lies within ``claim_radius`` of another agent's goal); failing that the nearest unclaimed secondary
    target, then the nearest claimed primary, then the nearest claimed secondary. It keeps the path and
    replans when it reaches its goal, the goal stops being a target (or a primary goal becomes secondary),
    a cell of the rest of the path stops being traversable, every ``replan_every`` seconds, and when it has
    made no progress along the path for ``stuck_after`` seconds (the goal is then given up).

Driving
    An agent heads for the farthest of the next ``lookahead`` path cells it sees in a straight line over
    traversable cells; when a forward sonar beam reads less than ``avoid_range`` it blends in the escape
    heading of :func:`amronet.motion._escape_one`, weighted by how close the nearest reading is. After a
    refused move it takes a uniform random heading for that step, as the random explorer does. An agent with
    no reachable target explores at random (:class:`amronet.algorithms.explorers.RandomExplorer`) and tries
    to plan again every ``replan_every`` seconds.

Only the run's generator is used (fresh headings and the random fallback), so a run is deterministic.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from amronet.algorithms.explorers import Explorer, register_explorer
from amronet.motion import _escape_one, random_walk
from amronet.sensing import beam_angles

__all__ = [
    "FREE_FLOOR",
    "HIT_GAIN",
    "OCCUPIED_CAP",
    "PRIMARY",
    "REPLAN_REASONS",
    "SECONDARY",
    "FrontierExplorer",
    "KnowledgeGrid",
    "find_path",
    "target_kinds",
]

HIT_GAIN = 3
"""Evidence a beam ending in a cell adds to its count."""
OCCUPIED_CAP = 12
"""Largest evidence count (a wall needs this many grazing passes to be cleared)."""
FREE_FLOOR = 4
"""Smallest evidence count is ``-FREE_FLOOR`` (a free cell turns occupied after two hits at most)."""
PRIMARY = 1
"""Target kind: going there releases a router or reveals uncovered space."""
SECONDARY = 2
"""Target kind: a frontier cell whose unknown surroundings are covered already."""

# why an agent last replanned (``FrontierExplorer.reason``)
_NO_GOAL, _REACHED, _NOT_TARGET, _DOWNGRADED, _STUCK, _PERIODIC, _BLOCKED = 1, 2, 3, 4, 5, 6, 7
REPLAN_REASONS = ("", "no goal", "reached", "not a target", "downgraded", "stuck", "periodic", "blocked")
"""Names of the codes in :attr:`FrontierExplorer.reason`."""

# 4-neighbours first, then the diagonals: the fixed expansion order that breaks BFS ties.
_DR = np.array([0, 1, 0, -1, 1, 1, -1, -1], dtype=np.int64)
_DC = np.array([1, 0, -1, 0, 1, -1, -1, 1], dtype=np.int64)


# --------------------------------------------------------------------------------------------------------
# numba kernels
# --------------------------------------------------------------------------------------------------------


@njit(cache=True)
def _trace(ox, oy, res, rows, cols, x0, y0, x1, y1, out_r, out_c):  # pragma: no cover - numba
    """Cells the segment crosses, in order (Amanatides-Woo); stops at the grid's edge. Returns how many."""
    c = int(math.floor((x0 - ox) / res))
    r = int(math.floor((y0 - oy) / res))
    c_end = int(math.floor((x1 - ox) / res))
    r_end = int(math.floor((y1 - oy) / res))
    dx = x1 - x0
    dy = y1 - y0
    step_c = 1 if dx > 0 else -1
    step_r = 1 if dy > 0 else -1
    inf = 1e300
    if dx != 0.0:
        t_max_x = (ox + (c + (1 if dx > 0 else 0)) * res - x0) / dx
        t_delta_x = res / abs(dx)
    else:
        t_max_x = inf
        t_delta_x = inf
    if dy != 0.0:
        t_max_y = (oy + (r + (1 if dy > 0 else 0)) * res - y0) / dy
        t_delta_y = res / abs(dy)
    else:
        t_max_y = inf
        t_delta_y = inf
    n = 0
    while n < out_r.shape[0]:
        if r < 0 or r >= rows or c < 0 or c >= cols:
            break
        out_r[n] = r
        out_c[n] = c
        n += 1
        if r == r_end and c == c_end:
            break
        if t_max_x < t_max_y:
            if t_max_x > 1.0:
                break
            c += step_c
            t_max_x += t_delta_x
        else:
            if t_max_y > 1.0:
                break
            r += step_r
            t_max_y += t_delta_y
    return n


@njit(cache=True)
def _integrate(score, seen, ox, oy, res, pos, heading, scans, angles, max_range, robots, n_own, robot_r,
               hit_gain, cap, floor, buf_r, buf_c):  # pragma: no cover - numba
    """Add the evidence of every beam of every sensing robot to the grid.

    ``robots[:n_own]`` are the sensing robots themselves (row ``a`` is ``pos[a]``): a robot's own position
    never hides its reading.
    """
    rows, cols = score.shape
    rr2 = robot_r * robot_r
    for a in range(pos.shape[0]):
        x0 = pos[a, 0]
        y0 = pos[a, 1]
        for k in range(angles.shape[0]):
            d = min(scans[a, k], max_range)
            ang = heading[a] + angles[k]
            ux = math.cos(ang)
            uy = math.sin(ang)
            hit = d < max_range - 1e-9
            on_robot = False
            if hit:
                hx = x0 + d * ux
                hy = y0 + d * uy
                for j in range(robots.shape[0]):
                    if j == a and j < n_own:
                        continue
                    ex = hx - robots[j, 0]
                    ey = hy - robots[j, 1]
                    if ex * ex + ey * ey <= rr2:
                        on_robot = True
                        break
                d += 1e-6  # the reading's point lies in the obstacle's cell
            n = _trace(ox, oy, res, rows, cols, x0, y0, x0 + d * ux, y0 + d * uy, buf_r, buf_c)
            last = n - 1 if hit else n
            for q in range(last):
                r = buf_r[q]
                c = buf_c[q]
                seen[r, c] = True
                if score[r, c] > -floor:
                    score[r, c] -= 1
            if hit and n > 0 and not on_robot:
                r = buf_r[n - 1]
                c = buf_c[n - 1]
                seen[r, c] = True
                score[r, c] = min(score[r, c] + hit_gain, cap)


@njit(cache=True)
def _paint_covered(covered, ox, oy, res, nodes, radius):  # pragma: no cover - numba
    """``covered[r, c]``: some node lies within ``radius`` of the cell's centre."""
    rows, cols = covered.shape
    covered[:, :] = False
    r2 = radius * radius
    for j in range(nodes.shape[0]):
        x = nodes[j, 0]
        y = nodes[j, 1]
        c_lo = max(0, int(math.floor((x - radius - ox) / res)))
        c_hi = min(cols - 1, int(math.floor((x + radius - ox) / res)))
        r_lo = max(0, int(math.floor((y - radius - oy) / res)))
        r_hi = min(rows - 1, int(math.floor((y + radius - oy) / res)))
        for r in range(r_lo, r_hi + 1):
            dy = oy + (r + 0.5) * res - y
            for c in range(c_lo, c_hi + 1):
                dx = ox + (c + 0.5) * res - x
                if dx * dx + dy * dy <= r2:
                    covered[r, c] = True


@njit(cache=True, inline="always")
def _free(score, seen, r, c):  # pragma: no cover - numba
    return seen[r, c] and score[r, c] <= 0


@njit(cache=True)
def _passable(score, seen, r, c, off_r, off_c):  # pragma: no cover - numba
    """Free, and no occupied cell within the clearance (cells beyond the grid's edge count as occupied)."""
    rows, cols = score.shape
    if r < 0 or r >= rows or c < 0 or c >= cols or not _free(score, seen, r, c):
        return False
    for q in range(off_r.shape[0]):
        rr = r + off_r[q]
        cc = c + off_c[q]
        if rr < 0 or rr >= rows or cc < 0 or cc >= cols or score[rr, cc] > 0:
            return False
    return True


@njit(cache=True)
def _window_any(seen, covered, r, c, rad, need_uncovered):  # pragma: no cover - numba
    """Is some unknown (and, with ``need_uncovered``, uncovered) cell within ``rad`` cells (a square)?"""
    rows, cols = seen.shape
    for rr in range(max(0, r - rad), min(rows, r + rad + 1)):
        for cc in range(max(0, c - rad), min(cols, c + rad + 1)):
            if not seen[rr, cc] and (not need_uncovered or not covered[rr, cc]):
                return True
    return False


@njit(cache=True)
def _kind_at(score, seen, covered, visited, off_r, off_c, fw, rw, r, c):  # pragma: no cover - numba
    """Target kind of one cell (0: none), by direct look-up (the per-step check of a goal)."""
    if visited[r, c] or not _passable(score, seen, r, c, off_r, off_c):
        return 0
    if not covered[r, c]:
        return 1
    if not _window_any(seen, covered, r, c, fw, False):
        return 0
    if _window_any(seen, covered, r, c, rw, True):
        return 1
    return 2


@njit(cache=True)
def _integral(seen, covered, unk_ii, uu_ii):  # pragma: no cover - numba
    """Integral images of the unknown cells and of the unknown, uncovered cells."""
    rows, cols = seen.shape
    for r in range(rows + 1):
        unk_ii[r, 0] = 0
        uu_ii[r, 0] = 0
    for c in range(cols + 1):
        unk_ii[0, c] = 0
        uu_ii[0, c] = 0
    for r in range(rows):
        su = 0
        sv = 0
        for c in range(cols):
            if not seen[r, c]:
                su += 1
                if not covered[r, c]:
                    sv += 1
            unk_ii[r + 1, c + 1] = unk_ii[r, c + 1] + su
            uu_ii[r + 1, c + 1] = uu_ii[r, c + 1] + sv


@njit(cache=True, inline="always")
def _box(ii, r, c, rad):  # pragma: no cover - numba
    rows = ii.shape[0] - 1
    cols = ii.shape[1] - 1
    r0 = max(0, r - rad)
    r1 = min(rows, r + rad + 1)
    c0 = max(0, c - rad)
    c1 = min(cols, c + rad + 1)
    return ii[r1, c1] - ii[r0, c1] - ii[r1, c0] + ii[r0, c0]


@njit(cache=True)
def _passable_mask(score, seen, off_r, off_c, out):  # pragma: no cover - numba
    """``out``: :func:`_passable` of every cell (free cells, then occupied cells knock out their neighbourhood)."""
    rows, cols = score.shape
    for r in range(rows):
        for c in range(cols):
            out[r, c] = seen[r, c] and score[r, c] <= 0
    for r in range(rows):
        for c in range(cols):
            if score[r, c] <= 0:
                continue
            for q in range(off_r.shape[0]):
                rr = r - off_r[q]
                cc = c - off_c[q]
                if 0 <= rr < rows and 0 <= cc < cols:
                    out[rr, cc] = False
    for q in range(off_r.shape[0]):  # cells whose clearance reaches beyond the grid's edge
        for r in range(rows):
            for c in range(cols):
                rr = r + off_r[q]
                cc = c + off_c[q]
                if rr < 0 or rr >= rows or cc < 0 or cc >= cols:
                    out[r, c] = False


@njit(cache=True, inline="always")
def _kind_ii(trav, covered, visited, fw, rw, unk_ii, uu_ii, r, c):  # pragma: no cover - numba
    """Same as :func:`_kind_at`, with traversability and the windows precomputed (the search's check)."""
    if visited[r, c] or not trav[r, c]:
        return 0
    if not covered[r, c]:
        return 1
    if _box(unk_ii, r, c, fw) == 0:
        return 0
    if _box(uu_ii, r, c, rw) > 0:
        return 1
    return 2


@njit(cache=True)
def _all_kinds(score, seen, covered, visited, off_r, off_c, fw, rw, trav, unk_ii, uu_ii, out):  # pragma: no cover
    rows, cols = score.shape
    _integral(seen, covered, unk_ii, uu_ii)
    _passable_mask(score, seen, off_r, off_c, trav)
    for r in range(rows):
        for c in range(cols):
            out[r, c] = _kind_ii(trav, covered, visited, fw, rw, unk_ii, uu_ii, r, c)


@njit(cache=True, inline="always")
def _open(score, seen, trav, r, c, sr, sc, escape):  # pragma: no cover - numba
    """May a path enter cell ``(r, c)``: traversable, or free and within ``escape`` cells of the start."""
    rows, cols = score.shape
    if r < 0 or r >= rows or c < 0 or c >= cols:
        return False
    if trav[r, c]:
        return True
    return max(abs(r - sr), abs(c - sc)) <= escape and _free(score, seen, r, c)


@njit(cache=True)
def _bfs(score, seen, covered, visited, trav, fw, rw, unk_ii, uu_ii, sr, sc, escape, claims, claim_r2, parent, queue,
         path):  # pragma: no cover - numba
    """Breadth-first search from ``(sr, sc)`` to the best target; the path (start excluded) goes to ``path``.

    Returns:
        ``(n, goal, kind)``: path length, flat goal cell (-1: none) and its target kind.
    """
    rows, cols = score.shape
    parent[:] = -1
    start = sr * cols + sc
    parent[start] = start
    queue[0] = start
    head = 0
    tail = 1
    g1 = -1
    g2 = -1
    b1 = -1
    b2 = -1
    while head < tail:
        u = queue[head]
        head += 1
        r = u // cols
        c = u - r * cols
        if u != start:
            kind = _kind_ii(trav, covered, visited, fw, rw, unk_ii, uu_ii, r, c)
            if kind:
                claimed = False
                for j in range(claims.shape[0]):
                    if claims[j, 0] < 0:
                        continue
                    er = r - claims[j, 0]
                    ec = c - claims[j, 1]
                    if er * er + ec * ec <= claim_r2:
                        claimed = True
                        break
                if kind == 1:
                    if not claimed:
                        g1 = u
                        break
                    if b1 < 0:
                        b1 = u
                elif claimed:
                    if b2 < 0:
                        b2 = u
                elif g2 < 0:
                    g2 = u
        for q in range(8):
            dr = _DR[q]
            dc = _DC[q]
            rr = r + dr
            cc = c + dc
            if rr < 0 or rr >= rows or cc < 0 or cc >= cols:
                continue
            v = rr * cols + cc
            if parent[v] >= 0:
                continue
            if not _open(score, seen, trav, rr, cc, sr, sc, escape):
                continue
            if q >= 4 and not (_open(score, seen, trav, r + dr, c, sr, sc, escape)
                               and _open(score, seen, trav, r, c + dc, sr, sc, escape)):
                continue
            parent[v] = u
            queue[tail] = v
            tail += 1
    goal = g1
    kind = 1
    if goal < 0:
        goal = g2
        kind = 2
    if goal < 0:
        goal = b1
        kind = 1
    if goal < 0:
        goal = b2
        kind = 2
    if goal < 0:
        return 0, -1, 0
    n = 0
    v = goal
    while v != start:
        n += 1
        v = parent[v]
    v = goal
    for q in range(n - 1, -1, -1):
        path[q] = v
        v = parent[v]
    return n, goal, kind


@njit(cache=True)
def _sees(score, seen, off_r, off_c, ox, oy, res, x0, y0, x1, y1, buf_r, buf_c):  # pragma: no cover - numba
    """Does the straight segment cross only traversable cells (the cell it starts in excepted)?"""
    rows, cols = score.shape
    n = _trace(ox, oy, res, rows, cols, x0, y0, x1, y1, buf_r, buf_c)
    if n == 0:
        return False
    for q in range(1, n):
        if not _passable(score, seen, buf_r[q], buf_c[q], off_r, off_c):
            return False
    return buf_r[n - 1] == int(math.floor((y1 - oy) / res)) and buf_c[n - 1] == int(math.floor((x1 - ox) / res))


@njit(cache=True)
def _navigate(now, xy, heading, who, scans, angles, reach, refused, fresh, score, seen, covered, visited, off_r,
              off_c, fw, rw, escape, ox, oy, res, goal, kind, paths, plen, ppos, last_plan, last_progress,
              replan_steps, stuck_steps, claim_r2, reach_tol, look, window, avoid_gain, parent, queue, trav, unk_ii,
              uu_ii, buf_r, buf_c, active, reason):  # pragma: no cover - numba
    """Replan where needed, then set the heading of every agent that has a path; ``active[m]``: it has one."""
    rows, cols = score.shape
    n_agents = who.shape[0]
    claims = np.full((n_agents, 2), -1, dtype=np.int64)
    ii_ready = False
    for m in range(n_agents):
        i = who[m]
        x = xy[i, 0]
        y = xy[i, 1]
        sc = int(math.floor((x - ox) / res))
        sr = int(math.floor((y - oy) / res))
        active[m] = False
        if sr < 0 or sr >= rows or sc < 0 or sc >= cols:
            goal[m] = -1
            plen[m] = 0
            continue
        need = 0
        if goal[m] < 0:
            if last_plan[m] < 0 or now - last_plan[m] >= replan_steps:
                need = _NO_GOAL
        else:
            gr = goal[m] // cols
            gc = goal[m] - gr * cols
            gx = ox + (gc + 0.5) * res
            gy = oy + (gr + 0.5) * res
            k_now = _kind_at(score, seen, covered, visited, off_r, off_c, fw, rw, gr, gc)
            if math.hypot(gx - x, gy - y) <= reach_tol:
                visited[gr, gc] = True
                need = _REACHED
            elif k_now == 0:
                need = _NOT_TARGET
            elif kind[m] == 1 and k_now != 1:
                need = _DOWNGRADED
            elif now - last_progress[m] >= stuck_steps:
                visited[gr, gc] = True  # give it up
                need = _STUCK
            elif now - last_plan[m] >= replan_steps:
                need = _PERIODIC
            else:
                for q in range(ppos[m], plen[m]):
                    v = paths[m, q]
                    vr = v // cols
                    if not _passable(score, seen, vr, v - vr * cols, off_r, off_c):
                        need = _BLOCKED
                        break
        if need:
            reason[m] = need
            if not ii_ready:
                _integral(seen, covered, unk_ii, uu_ii)
                _passable_mask(score, seen, off_r, off_c, trav)
                ii_ready = True
            for j in range(n_agents):
                claims[j, 0] = -1
                claims[j, 1] = -1
                if j != m and goal[j] >= 0:
                    claims[j, 0] = goal[j] // cols
                    claims[j, 1] = goal[j] - claims[j, 0] * cols
            n, g, k = _bfs(score, seen, covered, visited, trav, fw, rw, unk_ii, uu_ii, sr, sc, escape, claims,
                           claim_r2, parent, queue, paths[m])
            last_plan[m] = now
            if g != goal[m]:
                last_progress[m] = now
            goal[m] = g
            kind[m] = k
            plen[m] = n
            ppos[m] = 0
        if goal[m] < 0 or plen[m] == 0:
            continue
        active[m] = True
        # progress: the nearest of the next few path cells
        best = ppos[m]
        best_d = 1e300
        for q in range(ppos[m], min(ppos[m] + window, plen[m])):
            v = paths[m, q]
            vr = v // cols
            vx = ox + (v - vr * cols + 0.5) * res
            vy = oy + (vr + 0.5) * res
            d2 = (vx - x) ** 2 + (vy - y) ** 2
            if d2 < best_d:
                best_d = d2
                best = q
        if best > ppos[m]:
            ppos[m] = best
            last_progress[m] = now
        # aim: the farthest of the next few path cells in sight
        first = min(ppos[m] + 1, plen[m] - 1)
        aim = first
        for q in range(min(ppos[m] + look, plen[m] - 1), first, -1):
            v = paths[m, q]
            vr = v // cols
            vx = ox + (v - vr * cols + 0.5) * res
            vy = oy + (vr + 0.5) * res
            if _sees(score, seen, off_r, off_c, ox, oy, res, x, y, vx, vy, buf_r, buf_c):
                aim = q
                break
        v = paths[m, aim]
        vr = v // cols
        ax = ox + (v - vr * cols + 0.5) * res - x
        ay = oy + (vr + 0.5) * res - y
        if refused[m]:
            heading[i] = fresh[m]
            continue
        want = math.atan2(ay, ax) if ax * ax + ay * ay > 1e-18 else heading[i]
        esc, alarm = _escape_one(heading[i], scans[m], angles, reach)
        if alarm:
            w = 0.0
            for k in range(scans.shape[1]):
                w = max(w, (reach - scans[m, k]) / reach)
            w *= avoid_gain
            want = math.atan2(math.sin(want) + w * math.sin(esc), math.cos(want) + w * math.cos(esc))
        heading[i] = want


# --------------------------------------------------------------------------------------------------------
# the knowledge grid
# --------------------------------------------------------------------------------------------------------


class KnowledgeGrid:
    """What the agents know of the area: a coarse grid of unknown, free and occupied cells built from sonar.

    Args:
        extent: ``(xmin, xmax, ymin, ymax)`` of the area in metres.
        resolution: Cell size in metres.

    Attributes:
        score: Evidence count per cell ``(rows, cols)`` int16; positive: occupied.
        seen: Whether a beam ever crossed or ended in the cell ``(rows, cols)``.
        origin: World ``(x, y)`` of the lower-left corner of cell ``(0, 0)``.
        resolution: Cell size in metres.
    """

    def __init__(self, extent: tuple[float, float, float, float], resolution: float) -> None:
        if not resolution > 0:
            raise ValueError(f"resolution must be positive, not {resolution!r}")
        xmin, xmax, ymin, ymax = (float(v) for v in extent)
        self.origin = (xmin, ymin)
        self.resolution = float(resolution)
        cols = max(1, math.ceil((xmax - xmin) / resolution - 1e-9))
        rows = max(1, math.ceil((ymax - ymin) / resolution - 1e-9))
        self.score = np.zeros((rows, cols), dtype=np.int16)
        self.seen = np.zeros((rows, cols), dtype=np.bool_)
        self._buf_r = np.zeros(0, dtype=np.int64)
        self._buf_c = np.zeros(0, dtype=np.int64)

    @property
    def shape(self) -> tuple[int, int]:
        """``(rows, cols)``."""
        return self.score.shape

    @property
    def unknown(self) -> np.ndarray:
        """Cells no beam has reached."""
        return ~self.seen

    @property
    def occupied(self) -> np.ndarray:
        """Cells believed occupied."""
        return self.score > 0

    @property
    def free(self) -> np.ndarray:
        """Cells believed free."""
        return self.seen & (self.score <= 0)

    def cell_of(self, points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """``(rows, cols)`` of world points ``(M, 2)`` (may lie outside the grid)."""
        p = np.asarray(points, dtype=float).reshape(-1, 2)
        cols = np.floor((p[:, 0] - self.origin[0]) / self.resolution).astype(np.int64)
        rows = np.floor((p[:, 1] - self.origin[1]) / self.resolution).astype(np.int64)
        return rows, cols

    def centre(self, rows: np.ndarray, cols: np.ndarray) -> np.ndarray:
        """World centres ``(M, 2)`` of cells."""
        rows = np.asarray(rows, dtype=float)
        cols = np.asarray(cols, dtype=float)
        return np.stack([self.origin[0] + (cols + 0.5) * self.resolution,
                         self.origin[1] + (rows + 0.5) * self.resolution], axis=-1)

    def buffers(self, max_range: float) -> tuple[np.ndarray, np.ndarray]:
        """Scratch cell lists long enough for a segment of ``max_range`` metres."""
        need = int(2 * math.ceil(max_range / self.resolution) + 8)
        if len(self._buf_r) < need:
            self._buf_r = np.zeros(need, dtype=np.int64)
            self._buf_c = np.zeros(need, dtype=np.int64)
        return self._buf_r, self._buf_c

    def integrate(self, xy: np.ndarray, heading: np.ndarray, scans: np.ndarray, sensor_range: float,
                  robots_xy: np.ndarray | None = None, robot_radius: float = 0.3) -> None:
        """Add the evidence of range scans.

        Args:
            xy: Positions of the sensing robots ``(A, 2)``.
            heading: Their headings ``(A,)`` (beam ``k`` points at ``heading + 2 pi k / n_beams``).
            scans: Their readings ``(A, n_beams)``.
            sensor_range: Maximum range: a reading this long saw nothing.
            robots_xy: Other known robots ``(R, 2)``: a reading ending within ``robot_radius`` of one marks
                no obstacle. The sensing robots' own positions are added (each ignores itself).
            robot_radius: See ``robots_xy``.
        """
        xy = np.ascontiguousarray(xy, dtype=float).reshape(-1, 2)
        scans = np.ascontiguousarray(scans, dtype=float)
        if len(xy) == 0:
            return
        others = xy if robots_xy is None else np.concatenate([xy, np.asarray(robots_xy, dtype=float).reshape(-1, 2)])
        buf_r, buf_c = self.buffers(sensor_range)
        _integrate(self.score, self.seen, self.origin[0], self.origin[1], self.resolution, xy,
                   np.ascontiguousarray(heading, dtype=float), scans, beam_angles(scans.shape[1]), float(sensor_range),
                   np.ascontiguousarray(others), len(xy), float(robot_radius), HIT_GAIN, OCCUPIED_CAP, FREE_FLOOR,
                   buf_r, buf_c)

    def covered_by(self, nodes_xy: np.ndarray, radius: float) -> np.ndarray:
        """Cells whose centre lies within ``radius`` of one of the nodes ``(D, 2)``."""
        out = np.zeros(self.shape, dtype=np.bool_)
        _paint_covered(out, self.origin[0], self.origin[1], self.resolution,
                       np.ascontiguousarray(nodes_xy, dtype=float).reshape(-1, 2), float(radius))
        return out


def _offsets(clearance: float, resolution: float) -> tuple[np.ndarray, np.ndarray]:
    """Cell offsets whose centre lies within ``clearance`` of a cell's centre (the cell itself excluded)."""
    k = int(math.floor(clearance / resolution))
    dr, dc = np.mgrid[-k:k + 1, -k:k + 1]
    keep = (dr**2 + dc**2) * resolution**2 <= clearance**2 + 1e-12
    keep &= (dr != 0) | (dc != 0)
    return dr[keep].astype(np.int64), dc[keep].astype(np.int64)


def target_kinds(grid: KnowledgeGrid, covered: np.ndarray, visited: np.ndarray | None = None, *,
                 clearance: float = 0.3, frontier_window: int = 2, reach: float = 2.0) -> np.ndarray:
    """Target kind of every cell: 0 none, :data:`PRIMARY` or :data:`SECONDARY` (see the module's docstring).

    Args:
        grid: The knowledge grid.
        covered: Covered cells (:meth:`KnowledgeGrid.covered_by`).
        visited: Cells that are no longer targets; none by default.
        clearance: Inflation radius of occupied cells in metres.
        frontier_window: A frontier cell has an unknown cell within this many cells (a square window).
        reach: A primary frontier cell has an unknown, uncovered cell within this many metres (a square).

    Returns:
        ``(rows, cols)`` int8 array of target kinds.
    """
    rows, cols = grid.shape
    visited = np.zeros(grid.shape, dtype=np.bool_) if visited is None else np.asarray(visited, dtype=np.bool_)
    off_r, off_c = _offsets(clearance, grid.resolution)
    out = np.zeros(grid.shape, dtype=np.int8)
    trav = np.zeros(grid.shape, dtype=np.bool_)
    unk_ii = np.zeros((rows + 1, cols + 1), dtype=np.int32)
    uu_ii = np.zeros((rows + 1, cols + 1), dtype=np.int32)
    _all_kinds(grid.score, grid.seen, np.asarray(covered, dtype=np.bool_), visited, off_r, off_c,
               int(frontier_window), int(math.ceil(reach / grid.resolution)), trav, unk_ii, uu_ii, out)
    return out


def find_path(grid: KnowledgeGrid, start: tuple[int, int], covered: np.ndarray,
              visited: np.ndarray | None = None, claims: np.ndarray | None = None, *, clearance: float = 0.3,
              frontier_window: int = 2, reach: float = 2.0, claim_radius: float = 0.0,
              escape: int = 1) -> tuple[np.ndarray, int]:
    """Plan as an agent does: the shortest path from ``start`` to the best target (see the module's docstring).

    Args:
        grid: The knowledge grid.
        start: ``(row, col)`` of the agent's cell.
        covered: Covered cells (:meth:`KnowledgeGrid.covered_by`).
        visited: Cells that are no longer targets; none by default.
        claims: Goal cells ``(K, 2)`` of the other agents (rows of -1 are ignored).
        clearance: Inflation radius of occupied cells in metres.
        frontier_window: See :func:`target_kinds`.
        reach: See :func:`target_kinds`.
        claim_radius: Targets within this many metres of a claim are left to its agent when others exist.
        escape: Near the start (this many cells, Chebyshev) free cells that are not traversable may be crossed.

    Returns:
        ``(cells, kind)``: the path's cells ``(n, 2)`` as ``(row, col)``, start excluded, goal last (empty when
        no target is reachable), and the goal's target kind (0 when none).
    """
    rows, cols = grid.shape
    visited = np.zeros(grid.shape, dtype=np.bool_) if visited is None else np.asarray(visited, dtype=np.bool_)
    claims = np.full((0, 2), -1, dtype=np.int64) if claims is None else np.asarray(claims, dtype=np.int64)
    off_r, off_c = _offsets(clearance, grid.resolution)
    unk_ii = np.zeros((rows + 1, cols + 1), dtype=np.int32)
    uu_ii = np.zeros((rows + 1, cols + 1), dtype=np.int32)
    covered = np.asarray(covered, dtype=np.bool_)
    _integral(grid.seen, covered, unk_ii, uu_ii)
    trav = np.zeros(grid.shape, dtype=np.bool_)
    _passable_mask(grid.score, grid.seen, off_r, off_c, trav)
    parent = np.zeros(rows * cols, dtype=np.int64)
    queue = np.zeros(rows * cols, dtype=np.int64)
    path = np.zeros(rows * cols, dtype=np.int64)
    n, _, kind = _bfs(grid.score, grid.seen, covered, visited, trav, int(frontier_window),
                      int(math.ceil(reach / grid.resolution)), unk_ii, uu_ii, int(start[0]), int(start[1]),
                      int(escape), claims.reshape(-1, 2), float((claim_radius / grid.resolution) ** 2), parent, queue,
                      path)
    cells = path[:n]
    return np.stack([cells // cols, cells % cols], axis=1), int(kind)


# --------------------------------------------------------------------------------------------------------
# the explorer
# --------------------------------------------------------------------------------------------------------


@register_explorer("frontier")
class FrontierExplorer(Explorer):
    """Frontier exploration on a knowledge grid shared by the agents (see the module's docstring).

    The first five arguments are those of :class:`~amronet.algorithms.explorers.Explorer`; the others tune
    the strategy and keep their defaults when the explorer is picked by name.

    Args:
        turn_noise: Heading noise of the random fallback, radians per square-root second.
        avoid_range: Readings nearer than this (metres) trigger obstacle avoidance.
        dt: Step length in seconds.
        r_c: Communication radius.
        extent: ``(xmin, xmax, ymin, ymax)`` of the area in metres.
        resolution: Cell size of the knowledge grid in metres.
        clearance: Cells within this distance (metres, centre to centre) of an occupied cell are not
            traversable; about the agent's body radius (a Pioneer's is 0.22 m).
        cover_margin: A node covers cells within ``(1 - cover_margin) r_c``; keep it below the deployment's
            ``loss_margin`` (0.05) so that an agent reaching an uncovered cell releases a router.
        reach: A frontier cell is a primary target when an unknown, uncovered cell lies within this many
            metres; ``None``: the sonar's range.
        frontier_window: A cell is a frontier cell when an unknown cell lies within this many cells.
        claim_radius: Targets within this many metres of another agent's goal are left to it; ``None``:
            ``r_c / 2``.
        replan_every: Seconds between periodic replans.
        stuck_after: Seconds without progress along the path after which the goal is given up.
        lookahead: The agent aims at most this many path cells ahead.
        robot_radius: A reading ending within this many metres of a known robot marks no obstacle.
        avoid_gain: Weight of the escape heading at the closest reading.
    """

    def __init__(self, turn_noise: float, avoid_range: float, dt: float, r_c: float,
                 extent: tuple[float, float, float, float], *, resolution: float = 0.25, clearance: float = 0.3,
                 cover_margin: float = 0.02, reach: float | None = None, frontier_window: int = 2,
                 claim_radius: float | None = None, replan_every: float = 5.0, stuck_after: float = 10.0,
                 lookahead: int = 4, robot_radius: float = 0.3, avoid_gain: float = 2.0) -> None:
        super().__init__(turn_noise, avoid_range, dt, r_c, extent)
        self.grid = KnowledgeGrid(extent, resolution)
        self.clearance = clearance
        self.cover_radius = (1.0 - cover_margin) * r_c
        self.reach = reach
        self.frontier_window = frontier_window
        self.claim_radius = 0.5 * r_c if claim_radius is None else claim_radius
        self.replan_steps = max(1, round(replan_every / dt))
        self.stuck_steps = max(1, round(stuck_after / dt))
        self.lookahead = lookahead
        self.robot_radius = robot_radius
        self.avoid_gain = avoid_gain
        self.off_r, self.off_c = _offsets(clearance, resolution)
        rows, cols = self.grid.shape
        self.covered = np.zeros((rows, cols), dtype=np.bool_)
        self.visited = np.zeros((rows, cols), dtype=np.bool_)
        self._unk_ii = np.zeros((rows + 1, cols + 1), dtype=np.int32)
        self._uu_ii = np.zeros((rows + 1, cols + 1), dtype=np.int32)
        self._parent = np.zeros(rows * cols, dtype=np.int64)
        self._queue = np.zeros(rows * cols, dtype=np.int64)
        self._trav = np.zeros((rows, cols), dtype=np.bool_)
        self._nodes_key: tuple[int, float] | None = None
        self.steps = 0
        self.n_agents = -1

    def _start(self, n_agents: int) -> None:
        rows, cols = self.grid.shape
        self.n_agents = n_agents
        self.goal = np.full(n_agents, -1, dtype=np.int64)
        self.kind = np.zeros(n_agents, dtype=np.int64)
        self.paths = np.zeros((n_agents, rows * cols), dtype=np.int64)
        self.plen = np.zeros(n_agents, dtype=np.int64)
        self.ppos = np.zeros(n_agents, dtype=np.int64)
        self.last_plan = np.full(n_agents, -1, dtype=np.int64)
        self.last_progress = np.zeros(n_agents, dtype=np.int64)
        self.active = np.zeros(n_agents, dtype=np.bool_)
        self.reason = np.zeros(n_agents, dtype=np.int64)

    def goals_xy(self) -> np.ndarray:
        """Current goal of every agent ``(A, 2)`` in metres (NaN where it explores at random)."""
        cols = self.grid.shape[1]
        out = self.grid.centre(self.goal // cols, self.goal % cols)
        out[self.goal < 0] = np.nan
        return out

    def steer(self, heading: np.ndarray, who: np.ndarray, scans: np.ndarray, sensor_range: float,  # noqa: D102
              refused: np.ndarray, rng: np.random.Generator, xy: np.ndarray, deployed_xy: np.ndarray) -> None:
        who = np.asarray(who, dtype=np.int64)
        m = len(who)
        if m == 0:
            return
        if m != self.n_agents:
            self._start(m)
        grid = self.grid
        pos = xy[who]
        grid.integrate(pos, heading[who], scans, sensor_range, deployed_xy, self.robot_radius)
        key = (len(deployed_xy), float(np.sum(deployed_xy)))
        if key != self._nodes_key:
            self._nodes_key = key
            _paint_covered(self.covered, grid.origin[0], grid.origin[1], grid.resolution,
                           np.ascontiguousarray(deployed_xy, dtype=float).reshape(-1, 2), self.cover_radius)
        reach_m = sensor_range if self.reach is None else self.reach
        avoid = min(sensor_range, self.avoid_range)
        fresh = rng.uniform(-np.pi, np.pi, size=m)
        buf_r, buf_c = grid.buffers(max(sensor_range, (self.lookahead + 2) * grid.resolution * 1.5))
        res = grid.resolution
        _navigate(self.steps, xy, heading, who, np.ascontiguousarray(np.minimum(scans, avoid), dtype=float),
                  beam_angles(scans.shape[1]), float(avoid), np.asarray(refused, dtype=np.bool_), fresh, grid.score,
                  grid.seen, self.covered, self.visited, self.off_r, self.off_c, int(self.frontier_window),
                  int(math.ceil(reach_m / res)), int(math.ceil(self.clearance / res)) + 1, grid.origin[0],
                  grid.origin[1], res, self.goal, self.kind, self.paths, self.plen, self.ppos, self.last_plan,
                  self.last_progress, self.replan_steps, self.stuck_steps, float((self.claim_radius / res) ** 2),
                  0.75 * res, int(self.lookahead), int(self.lookahead) + 4, float(self.avoid_gain), self._parent,
                  self._queue, self._trav, self._unk_ii, self._uu_ii, buf_r, buf_c, self.active, self.reason)
        self.steps += 1
        idle = ~self.active
        if idle.any():
            random_walk(heading, who[idle], np.minimum(scans[idle], avoid), avoid, np.asarray(refused)[idle], rng,
                        self.turn_noise * np.sqrt(self.dt))
