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

from amronet.algorithms.agent_assisted.explorers.frontier.knowledge import passable, trace_cells, update_passable
from amronet.algorithms.agent_assisted.explorers.frontier.planning import (
    UNCOVERED,
    kind_at,
    nearest_uncovered,
    search_target,
    update_window_counts,
)
from amronet.algorithms.agent_assisted.explorers.frontier.state import (
    APPROACHED,
    BLOCKED,
    NO_GOAL,
    NODE_DEPLOYED,
    NOT_TARGET,
    PERIODIC,
    REACHED,
    STUCK,
    AgentPlans,
    MapLayers,
    NavBuffers,
    NavSettings,
    StepInputs,
)
from amronet.engine.motion import escape_one

__all__ = ["navigate", "navigate_kernel"]


@njit(cache=True)
def _sees(score, seen, rb, off_r, off_c, origin, start, end, buf_r, buf_c):  # pragma: no cover - numba
    """Does the straight segment from ``start`` to ``end`` (``(x, y)`` each) cross only traversable cells?

    The cell it starts in is excepted; ``origin`` is ``(ox, oy, res)``, the grid's lower-left corner and cell size.
    """
    ox, oy, res = origin
    x0, y0 = start
    x1, y1 = end
    rows, cols = score.shape
    n = trace_cells(ox, oy, res, rows, cols, x0, y0, x1, y1, buf_r, buf_c)
    if n == 0:
        return False
    for q in range(1, n):
        if not passable(score, seen, rb, buf_r[q], buf_c[q], off_r, off_c):
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
    esc, _ = escape_one(heading, scans, angles, reach)
    return esc


def navigate(step: StepInputs, layers: MapLayers, cfg: NavSettings, plans: AgentPlans, work: NavBuffers) -> None:
    """Replan where needed, then set the heading of every agent that has a path or an approach.

    An agent first plans around the deployed nodes; when that finds no target it plans through them
    (:attr:`~amronet.algorithms.agent_assisted.explorers.frontier.state.AgentPlans.through_nodes`). Agents left inactive
    (``plans.active``) explore at random: the caller steers them.

    The search's views in ``work`` are kept between calls and brought up to date when an agent plans, once per
    call each, for the rows changed since the grid stamps in ``work.synced``: the traversable cells around the
    nodes and through them by :func:`update_passable`, the window counts by :func:`update_window_counts`.

    The work is done by a compiled kernel, given the named tuples as plain tuples: numba types those in its
    compiled fast path, but a named tuple field by field in Python on every call (a few microseconds each).

    Args:
        step: This step's inputs; ``step.heading`` is set for the active agents.
        layers: The shared grid and the explorer's layers; ``layers.visited`` is updated.
        cfg: The parameters.
        plans: The agents' plans, updated in place.
        work: Scratch space and the search's views, updated in place.
    """
    navigate_kernel(tuple(step), tuple(layers), tuple(cfg), tuple(plans), tuple(work))


@njit(cache=True)
def navigate_kernel(step, layers, cfg, plans, work):  # pragma: no cover - numba
    """The compiled kernel of :func:`navigate` (for other kernels too).

    It unpacks the tuples into their fields' names, in order.
    """
    now, nodes_changed, xy, heading, who, scans, angles, refused, fresh = step
    score, seen, row_stamp, stamp, robots, no_robots, covered, gap, visited = layers
    (origin_x, origin_y, resolution, off_r, off_c, window, escape, replan_every, stuck_after, lookahead,
     approach_steps, reach, stuck_radius, claim_r2, reach_tol, lane) = cfg
    (goal, kind, path, path_len, path_pos, through_nodes, last_plan, reason, anchor, last_move, approach,
     approach_until, active) = plans
    search, trav, marks, counts, synced, cells_r, cells_c, least_gap = work
    ox = origin_x
    oy = origin_y
    res = resolution
    win = window
    rows, cols = score.shape
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
            goal[m] = -1
            path_len[m] = 0
            approach[m] = -1
            continue
        if math.hypot(x - anchor[m, 0], y - anchor[m, 1]) > stuck_radius:
            anchor[m, 0] = x
            anchor[m, 1] = y
            last_move[m] = now
        # the last stretch to an uncovered cell beside the traversable ones: straight at it
        a = approach[m]
        if a >= 0:
            ar = a // cols
            ac = a - ar * cols
            ax = ox + (ac + 0.5) * res - x
            ay = oy + (ar + 0.5) * res - y
            if refused[m] or covered[ar, ac] or now >= approach_until[m] or math.hypot(ax, ay) < 0.5 * res:
                approach[m] = -1
            else:
                active[m] = True
                heading[i] = math.atan2(ay, ax)
                continue
        # why replan (0: no need)
        rbm = no_robots if through_nodes[m] else robots
        need = 0
        g = goal[m]
        if a >= 0:
            need = APPROACHED
        elif g < 0:
            if last_plan[m] < 0 or now - last_plan[m] >= replan_every:
                need = NO_GOAL
        else:
            gr = g // cols
            gc = g - gr * cols
            if math.hypot(ox + (gc + 0.5) * res - x, oy + (gr + 0.5) * res - y) <= reach_tol:
                visited[gr, gc] = True
                need = REACHED
                if kind[m] == UNCOVERED and covered[gr, gc]:  # then on to a seen uncovered cell beside it
                    a = nearest_uncovered(seen, covered, gr, gc, win, x, y, ox, oy, res)
                    if a >= 0:
                        approach[m] = a
                        approach_until[m] = now + approach_steps
                        ar = a // cols
                        active[m] = True
                        heading[i] = math.atan2(oy + (ar + 0.5) * res - y, ox + (a - ar * cols + 0.5) * res - x)
                        continue
            elif kind_at(score, seen, rbm, covered, visited, off_r, off_c, win, gr, gc) == 0:
                need = NOT_TARGET
            elif nodes_changed:
                need = NODE_DEPLOYED
            elif now - last_move[m] >= stuck_after:
                visited[gr, gc] = True  # give it up
                need = STUCK
            elif now - last_plan[m] >= replan_every:
                need = PERIODIC
            else:
                for q in range(path_pos[m], path_len[m]):
                    v = path[m, q]
                    vr = v // cols
                    vc = v - vr * cols
                    if max(abs(vr - sr), abs(vc - sc)) > escape and not passable(score, seen, rbm, vr, vc, off_r,
                                                                                 off_c):
                        need = BLOCKED
                        break
        # plan: around the deployed nodes, else through them
        if need:
            reason[m] = need
            if not ready:
                update_window_counts(score, seen, covered, win, row_stamp > synced[0], row_stamp > synced[1],
                                     marks, counts)
                update_passable(score, seen, robots, off_r, off_c, row_stamp > synced[2], trav[0])
                synced[0] = stamp
                synced[1] = stamp
                synced[2] = stamp
                ready = True
            for j in range(n_agents):
                claims[j, 0] = -1
                claims[j, 1] = -1
                if j != m and goal[j] >= 0:
                    claims[j, 0] = goal[j] // cols
                    claims[j, 1] = goal[j] - claims[j, 0] * cols
            targets = (visited, counts, gap, win, least_gap[0])
            n, g, k = search_target(score, seen, trav[0], targets, (claims, claim_r2), sr, sc, escape, search, path[m])
            through_nodes[m] = False
            if g < 0:
                if not ready_soft:
                    update_passable(score, seen, no_robots, off_r, off_c, row_stamp > synced[3], trav[1])
                    synced[3] = stamp
                    ready_soft = True
                n, g, k = search_target(score, seen, trav[1], targets, (claims, claim_r2), sr, sc, escape, search,
                                        path[m])
                through_nodes[m] = g >= 0
            rbm = no_robots if through_nodes[m] else robots
            last_plan[m] = now
            if need == STUCK:
                last_move[m] = now
            goal[m] = g
            kind[m] = k
            path_len[m] = n
            path_pos[m] = 0
        plen = path_len[m]
        if goal[m] < 0 or plen == 0:
            continue
        active[m] = True
        # progress: the nearest of the next few path cells
        ppos = path_pos[m]
        best_d = np.inf
        for q in range(ppos, min(ppos + lookahead + 4, plen)):
            v = path[m, q]
            vr = v // cols
            d2 = (ox + (v - vr * cols + 0.5) * res - x) ** 2 + (oy + (vr + 0.5) * res - y) ** 2
            if d2 < best_d:
                best_d = d2
                path_pos[m] = q
        ppos = path_pos[m]
        # aim: the farthest of the next few path cells in sight
        first = min(ppos + 1, plen - 1)
        aim = first
        for q in range(min(ppos + lookahead, plen - 1), first, -1):
            v = path[m, q]
            vr = v // cols
            if _sees(score, seen, rbm, off_r, off_c, (ox, oy, res), (x, y),
                     (ox + (v - vr * cols + 0.5) * res, oy + (vr + 0.5) * res), cells_r, cells_c):
                aim = q
                break
        if refused[m]:
            heading[i] = fresh[m]
            continue
        v = path[m, aim]
        vr = v // cols
        ax = ox + (v - vr * cols + 0.5) * res - x
        ay = oy + (vr + 0.5) * res - y
        want = math.atan2(ay, ax) if ax * ax + ay * ay > 1e-18 else heading[i]
        heading[i] = _clear_heading(want, heading[i], scans[m], angles, reach, lane)
