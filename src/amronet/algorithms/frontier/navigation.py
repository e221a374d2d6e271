"""The agents' navigation kernel: replan where needed, then steer along the path (see the package docstring).

Each agent heads for the farthest of the next ``lookahead`` path cells it sees in a straight line over
traversable cells, turned as little as needed to keep a lane clear of near sonar readings
(:func:`_clear_heading`); an agent that reached an uncovered target drives straight at the nearest seen
uncovered cell for a while.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from amronet.algorithms.frontier.knowledge import _passable, _passable_rows, _trace
from amronet.algorithms.frontier.planning import _bfs, _kind_direct, _nearest_uncovered, _window_counts
from amronet.algorithms.frontier.state import (
    _APPR,
    _APPR_UNTIL,
    _APPROACHED,
    _BLOCKED,
    _COVERAGE,
    _F_CLAIM_R2,
    _F_LANE,
    _F_OX,
    _F_OY,
    _F_REACH,
    _F_REACH_TOL,
    _F_RES,
    _F_STUCK_R,
    _GOAL,
    _I_APPROACH,
    _I_ESCAPE,
    _I_LOOK,
    _I_REPLAN,
    _I_STUCK,
    _I_WINDOW,
    _KIND,
    _LAST_MOVE,
    _LAST_PLAN,
    _NO_GOAL,
    _NOT_TARGET,
    _PERIODIC,
    _PLEN,
    _PPOS,
    _REACHED,
    _REASON,
    _SOFT,
    _STUCK,
)
from amronet.motion import _escape_one

__all__: list[str] = []

@njit(cache=True)
def _sees(score, seen, rb, off_r, off_c, ox, oy, res, x0, y0, x1, y1, buf_r, buf_c):  # pragma: no cover - numba
    """Does the straight segment cross only traversable cells (the cell it starts in excepted)?"""
    rows, cols = score.shape
    n = _trace(ox, oy, res, rows, cols, x0, y0, x1, y1, buf_r, buf_c)
    if n == 0:
        return False
    for q in range(1, n):
        if not _passable(score, seen, rb, buf_r[q], buf_c[q], off_r, off_c):
            return False
    return buf_r[n - 1] == int(math.floor((y1 - oy) / res)) and buf_c[n - 1] == int(math.floor((x1 - ox) / res))


@njit(cache=True)
def _clear_heading(want, heading, scans, angles, reach, half_width):  # pragma: no cover - numba
    """The heading nearest ``want`` whose swept lane is clear of what the beams see, else the escape heading.

    A reading ``d < reach`` of a beam at angle ``phi`` from a candidate heading is in the way when it lies
    ahead (``d cos phi > 0``) and within ``half_width`` of the lane's axis (``|d sin phi| < half_width``).
    Candidates: ``want``, then ``want`` turned by 15, -15, 30, -30, ... up to 120 degrees.
    """
    step = math.pi / 12.0
    for j in range(17):
        turn = step * ((j + 1) // 2) * (1.0 if j % 2 == 1 else -1.0)
        cand = want + turn
        clear = True
        for k in range(scans.shape[0]):
            d = scans[k]
            if d >= reach:
                continue
            phi = heading + angles[k] - cand
            if d * math.cos(phi) > 0.0 and abs(d * math.sin(phi)) < half_width:
                clear = False
                break
        if clear:
            return cand
    esc, _ = _escape_one(heading, scans, angles, reach)
    return esc


@njit(cache=True)
def _navigate(now, refresh, xy, heading, who, scans, angles, refused, fresh, score, seen, rb, no_rb, covered, gap,
              visited, off_r, off_c, ip, fp, st, anchor, paths, search, trav, marks, counts, row_stamp, stamp, synced,
              buf_r, buf_c, active):  # pragma: no cover - numba
    """Replan where needed, then set the heading of every agent that has a path; ``active[m]``: it has one.

    ``st`` holds the per-agent state (columns ``_GOAL`` ...), ``ip`` and ``fp`` the settings (``_I_*``,
    ``_F_*``). An agent first plans around the deployed nodes ``rb``; when that finds no target it plans through
    them (``st[m, _SOFT]``; ``no_rb`` is all ``False``).

    The search's views are kept between calls and brought up to date when an agent plans, for the rows
    changed since: ``trav[0]`` (traversable cells) and ``trav[1]`` (the same through the nodes) by
    :func:`_passable_rows`, ``marks`` and ``counts`` by :func:`_window_counts`. ``synced`` holds the grid's
    stamp (``stamp`` now, ``row_stamp`` per row) each reflects: frontier counts, uncovered counts, ``trav[0]``,
    ``trav[1]``; -1 when all must be computed again (the caller's business when ``covered`` or ``rb`` change).
    """
    rows, cols = score.shape
    win = ip[_I_WINDOW]
    escape = ip[_I_ESCAPE]
    ox = fp[_F_OX]
    oy = fp[_F_OY]
    res = fp[_F_RES]
    n_agents = who.shape[0]
    claims = np.full((n_agents, 2), -1, dtype=np.int64)
    ready = False
    ready_soft = False
    for m in range(n_agents):
        i = who[m]
        x = xy[i, 0]
        y = xy[i, 1]
        sc = int(math.floor((x - ox) / res))
        sr = int(math.floor((y - oy) / res))
        active[m] = False
        if sr < 0 or sr >= rows or sc < 0 or sc >= cols:
            st[m, _GOAL] = -1
            st[m, _PLEN] = 0
            st[m, _APPR] = -1
            continue
        if math.hypot(x - anchor[m, 0], y - anchor[m, 1]) > fp[_F_STUCK_R]:
            anchor[m, 0] = x
            anchor[m, 1] = y
            st[m, _LAST_MOVE] = now
        # the last stretch to an uncovered cell beside the traversable ones: straight at it
        a = st[m, _APPR]
        if a >= 0:
            ar = a // cols
            ac = a - ar * cols
            ax = ox + (ac + 0.5) * res - x
            ay = oy + (ar + 0.5) * res - y
            if refused[m] or covered[ar, ac] or now >= st[m, _APPR_UNTIL] or math.hypot(ax, ay) < 0.5 * res:
                st[m, _APPR] = -1
            else:
                active[m] = True
                heading[i] = math.atan2(ay, ax)
                continue
        rbm = no_rb if st[m, _SOFT] else rb
        need = 0
        goal = st[m, _GOAL]
        if a >= 0:
            need = _APPROACHED
        elif goal < 0:
            if st[m, _LAST_PLAN] < 0 or now - st[m, _LAST_PLAN] >= ip[_I_REPLAN]:
                need = _NO_GOAL
        else:
            gr = goal // cols
            gc = goal - gr * cols
            if math.hypot(ox + (gc + 0.5) * res - x, oy + (gr + 0.5) * res - y) <= fp[_F_REACH_TOL]:
                visited[gr, gc] = True
                need = _REACHED
                if st[m, _KIND] == 1 and covered[gr, gc]:
                    a = _nearest_uncovered(seen, covered, gr, gc, win, x, y, ox, oy, res)
                    if a >= 0:
                        st[m, _APPR] = a
                        st[m, _APPR_UNTIL] = now + ip[_I_APPROACH]
                        ar = a // cols
                        active[m] = True
                        heading[i] = math.atan2(oy + (ar + 0.5) * res - y, ox + (a - ar * cols + 0.5) * res - x)
                        continue
            elif _kind_direct(score, seen, rbm, covered, visited, off_r, off_c, win, gr, gc) == 0:
                need = _NOT_TARGET
            elif refresh:
                need = _COVERAGE
            elif now - st[m, _LAST_MOVE] >= ip[_I_STUCK]:
                visited[gr, gc] = True  # give it up
                need = _STUCK
            elif now - st[m, _LAST_PLAN] >= ip[_I_REPLAN]:
                need = _PERIODIC
            else:
                for q in range(st[m, _PPOS], st[m, _PLEN]):
                    v = paths[m, q]
                    vr = v // cols
                    vc = v - vr * cols
                    if max(abs(vr - sr), abs(vc - sc)) > escape and not _passable(score, seen, rbm, vr, vc, off_r,
                                                                                  off_c):
                        need = _BLOCKED
                        break
        if need:
            st[m, _REASON] = need
            if not ready:
                _window_counts(score, seen, covered, win, row_stamp > synced[0], row_stamp > synced[1], marks, counts)
                _passable_rows(score, seen, rb, off_r, off_c, row_stamp > synced[2], trav[0])
                synced[0] = stamp
                synced[1] = stamp
                synced[2] = stamp
                ready = True
            for j in range(n_agents):
                claims[j, 0] = -1
                claims[j, 1] = -1
                if j != m and st[j, _GOAL] >= 0:
                    claims[j, 0] = st[j, _GOAL] // cols
                    claims[j, 1] = st[j, _GOAL] - claims[j, 0] * cols
            n, g, k = _bfs(score, seen, visited, trav[0], counts, gap, win, sr, sc, escape, claims, fp[_F_CLAIM_R2],
                           search, paths[m])
            st[m, _SOFT] = 0
            if g < 0:
                if not ready_soft:
                    _passable_rows(score, seen, no_rb, off_r, off_c, row_stamp > synced[3], trav[1])
                    synced[3] = stamp
                    ready_soft = True
                n, g, k = _bfs(score, seen, visited, trav[1], counts, gap, win, sr, sc, escape, claims,
                               fp[_F_CLAIM_R2], search, paths[m])
                st[m, _SOFT] = 1 if g >= 0 else 0
            rbm = no_rb if st[m, _SOFT] else rb
            st[m, _LAST_PLAN] = now
            if need == _STUCK:
                st[m, _LAST_MOVE] = now
            st[m, _GOAL] = g
            st[m, _KIND] = k
            st[m, _PLEN] = n
            st[m, _PPOS] = 0
        plen = st[m, _PLEN]
        if st[m, _GOAL] < 0 or plen == 0:
            continue
        active[m] = True
        # progress: the nearest of the next few path cells
        ppos = st[m, _PPOS]
        best_d = np.inf
        for q in range(ppos, min(ppos + ip[_I_LOOK] + 4, plen)):
            v = paths[m, q]
            vr = v // cols
            d2 = (ox + (v - vr * cols + 0.5) * res - x) ** 2 + (oy + (vr + 0.5) * res - y) ** 2
            if d2 < best_d:
                best_d = d2
                st[m, _PPOS] = q
        ppos = st[m, _PPOS]
        # aim: the farthest of the next few path cells in sight
        first = min(ppos + 1, plen - 1)
        aim = first
        for q in range(min(ppos + ip[_I_LOOK], plen - 1), first, -1):
            v = paths[m, q]
            vr = v // cols
            if _sees(score, seen, rbm, off_r, off_c, ox, oy, res, x, y, ox + (v - vr * cols + 0.5) * res,
                     oy + (vr + 0.5) * res, buf_r, buf_c):
                aim = q
                break
        if refused[m]:
            heading[i] = fresh[m]
            continue
        v = paths[m, aim]
        vr = v // cols
        ax = ox + (v - vr * cols + 0.5) * res - x
        ay = oy + (vr + 0.5) * res - y
        want = math.atan2(ay, ax) if ax * ax + ay * ay > 1e-18 else heading[i]
        heading[i] = _clear_heading(want, heading[i], scans[m], angles, fp[_F_REACH], fp[_F_LANE])
