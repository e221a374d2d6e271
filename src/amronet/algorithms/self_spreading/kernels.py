"""The kernels of self-spreading's fast step (:mod:`amronet.algorithms.self_spreading.fast`): sense, decide, move.

Each calls, robot by robot and in the reference's order, the same compiled functions the phase-by-phase path
calls (range rings, reference tracking, random walk, go-to-goal, drive), so the result is the same bit for bit.
Kept apart from the Python that drives them so that the kernel cache's key (:mod:`amronet.kernel_cache`) covers
only what the kernels read.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit, prange

from amronet.algorithms.common.goto import steer_one
from amronet.algorithms.common.references import track_row
from amronet.algorithms.common.swarm_stretch_kernels import BAD_DRAW, CANDIDATES, QUIET, after_step
from amronet.engine.bitgen import draw_normal_uniform
from amronet.engine.motion import commit_one, drive_one, plan_one, walk_one
from amronet.engine.robots import State
from amronet.engine.sensing import cast_bodies_one, cast_grid_one

__all__ = [
    "commit_moves",
    "list_movers",
    "sense_steer_drive",
    "sense_steer_plan_threaded",
    "spreading_stretch",
    "track_explorers",
]

_EXPLORE = State.EXPLORE
_REFERENCE = State.REFERENCE
_TRIANGLE = State.TRIANGLE
_TRIANGLE_SETTLED = State.TRIANGLE_SETTLED



@njit(cache=True)
def list_movers(state, movers, walkers):  # pragma: no cover - numba
    """The routers that move this step (exploring or on their way to a triangle goal), and the walkers among them."""
    m = 0
    w = 0
    for i in range(state.shape[0]):
        s = state[i]
        if s == _EXPLORE or s == _TRIANGLE:
            movers[m] = i
            m += 1
            if s == _EXPLORE:
                walkers[w] = i
                w += 1
    return m, w


@njit(cache=True)
def track_explorers(state, status, current, deployed_lookup, is_ref, indptr, indices, dist, want_other, r_eff,
                    xy, r_c, local, disabled, explorers, new_current, nearest, other, movers,
                    walkers):  # pragma: no cover - numba
    """Reference tracking of every exploring router; the stops too when no triangular deployment may start.

    A router that met a reference of another status is a *candidate* unless the rules of
    :func:`~amronet.algorithms.common.triangular.select_triangles` that need no graph already rule its triangle out: its
    two references are within ``r_c`` of each other, or (``local``) both are disabled.

    Returns:
        ``(k, candidates, n_movers, n_walkers)``: the number of explorers (their ids, new references, nearest
        reference distances and references of another status in the first ``k`` entries of the output arrays) and
        how many are candidates. With candidates nothing is changed (the caller settles the explorers and lists
        the movers); without, the routers that move on (:func:`list_movers`) are listed too.
    """
    n = state.shape[0]
    for j in range(n):
        is_ref[j] = deployed_lookup[state[j]]
    k = 0
    candidates = 0
    for i in range(n):
        if state[i] != _EXPLORE:
            continue
        c, d, o, _ = track_row(i, current[i], is_ref, status, indptr, indices, dist, want_other)
        explorers[k] = i
        new_current[k] = c
        nearest[k] = d
        other[k] = o
        if o >= 0:
            dx = xy[c, 0] - xy[o, 0]
            dy = xy[c, 1] - xy[o, 1]
            if math.sqrt(dx * dx + dy * dy) > r_c and not (local and disabled[c] and disabled[o]):
                candidates += 1
        k += 1
    if candidates:
        return k, candidates, 0, 0
    for m in range(k):
        i = explorers[m]
        c = new_current[m]
        current[i] = c
        if c >= 0 and nearest[m] >= r_eff:
            state[i] = _REFERENCE
            status[i] = status[c]
    n_movers, n_walkers = list_movers(state, movers, walkers)
    return k, 0, n_movers, n_walkers


@njit(cache=True, inline="always")
def sense_one(blocked, clear, ox, oy, res, xy, heading, radius, big, i, angles, sensor_range, s_indptr, s_indices,
              s_dist, sense_bodies, out):  # pragma: no cover - numba
    """Robot ``i``'s ring into ``out``: the grid's beams, then (``sense_bodies``) shortened by the bodies near it."""
    cast_grid_one(blocked, clear, ox, oy, res, xy[i, 0], xy[i, 1], heading[i], angles, sensor_range, out)
    if sense_bodies:
        cast_bodies_one(i, s_indptr, s_indices, s_dist, xy, heading[i], angles, sensor_range, radius, big, out)


@njit(cache=True, inline="always")
def decide_one(i, w, state, heading, xy, max_speed, refused, normal, uniform, turn_sigma, scan, angles, sensor_range,
               goal, anchors, last_to_goal, blocked_steps, give_up, min_progress, r_eff, dt):  # pragma: no cover
    """Mover ``i``'s decision from its ring ``scan``, and the length of its step.

    A walker (the ``w``-th) walks, a triangle router steers to its goal (and settles when it cannot go on): the
    operations of :func:`sense_steer_drive`'s decide loop, which keeps them (and its sense loop) written out: calling
    this function and :func:`sense_one` from there made the one-thread step 15-20 % slower at N = 3 000.
    """
    if state[i] == _EXPLORE:
        noise = turn_sigma * normal[w]
        fresh = -np.pi + (2.0 * np.pi) * uniform[w]
        heading[i] = walk_one(heading[i], scan, angles, sensor_range, refused[i], noise, fresh)
        speed = max_speed[i]
    else:
        step, done = steer_one(i, xy, heading, goal, anchors, scan, angles, sensor_range, max_speed[i] * dt, r_eff,
                               last_to_goal, blocked_steps, give_up, min_progress)
        if done:
            state[i] = _TRIANGLE_SETTLED
        speed = step / dt
    return speed * dt


@njit(cache=True)
def sense_steer_drive(blocked, clear, ox, oy, res, xy, heading, state, max_speed, radius, distance, refused,
                      movers, normal, uniform, turn_sigma, angles, sensor_range, s_indptr, s_indices, s_dist,
                      sense_bodies, goal, anchors, last_to_goal, blocked_steps, give_up, min_progress, r_eff, dt,
                      bodies, d_indptr, d_indices, d_dist, scans, length):  # pragma: no cover - numba
    """Sense, steer and drive the ``movers``; the same per-robot functions, in the same order, as the reference.

    ``normal`` and ``uniform``: the walkers' draws (:func:`~amronet.engine.streams.normal_then_uniform`), scaled here as
    :func:`~amronet.engine.motion.random_walk` scales them (the same operations on the same numbers).
    """
    big = radius.max()
    for m in range(movers.shape[0]):  # sense: every mover's ring, from where everybody stands now
        i = movers[m]
        cast_grid_one(blocked, clear, ox, oy, res, xy[i, 0], xy[i, 1], heading[i], angles, sensor_range, scans[m])
        if sense_bodies:
            cast_bodies_one(i, s_indptr, s_indices, s_dist, xy, heading[i], angles, sensor_range, radius, big,
                            scans[m])
    w = 0
    longest = 0.0
    for m in range(movers.shape[0]):  # decide: walkers walk, triangle routers steer to their goals
        i = movers[m]
        if state[i] == _EXPLORE:
            noise = turn_sigma * normal[w]
            fresh = -np.pi + (2.0 * np.pi) * uniform[w]
            heading[i] = walk_one(heading[i], scans[m], angles, sensor_range, refused[i], noise, fresh)
            w += 1
            speed = max_speed[i]
        else:
            step, done = steer_one(i, xy, heading, goal, anchors, scans[m], angles, sensor_range, max_speed[i] * dt,
                                   r_eff, last_to_goal, blocked_steps, give_up, min_progress)
            if done:
                state[i] = _TRIANGLE_SETTLED
            speed = step / dt
        length[m] = speed * dt
        if m == 0 or length[m] > longest:
            longest = length[m]
    near = 2.0 * big + 2.0 * longest
    refused[:] = False
    for m in range(movers.shape[0]):  # move, one after another
        i = movers[m]
        r, travelled = drive_one(blocked, clear, ox, oy, res, i, heading[i], length[m], xy, radius, bodies,
                                 d_indptr, d_indices, d_dist, near)
        refused[i] = r
        distance[i] += travelled
    _arrive(movers, state, xy, goal)


@njit(cache=True, inline="always")
def _longest(length, n):  # pragma: no cover - numba
    longest = 0.0
    for m in range(n):
        if m == 0 or length[m] > longest:
            longest = length[m]
    return longest


@njit(cache=True)
def _arrive(movers, state, xy, goal):  # pragma: no cover - numba
    """A triangle router on its goal has arrived."""
    for m in range(movers.shape[0]):
        i = movers[m]
        if state[i] == _TRIANGLE:
            dx = xy[i, 0] - goal[i, 0]
            dy = xy[i, 1] - goal[i, 1]
            if math.sqrt(dx * dx + dy * dy) <= 1e-9:
                state[i] = _TRIANGLE_SETTLED


@njit(cache=True, parallel=True)
def sense_steer_plan_threaded(blocked, clear, ox, oy, res, xy, heading, state, max_speed, radius, refused, movers,
                              normal, uniform, turn_sigma, angles, sensor_range, s_indptr, s_indices, s_dist,
                              sense_bodies, goal, anchors, last_to_goal, blocked_steps, give_up, min_progress, r_eff,
                              dt, scans, length, slot, free, planned):  # pragma: no cover - numba
    """:func:`sense_steer_drive` up to the moves' obstacle checks, on several threads; :func:`commit_moves` ends it.

    Every mover's ring, decision and path against the map depend on where the robots stand before anybody moves and
    on the mover's own state, nothing else, so each mover is done in one go by one thread: the same numbers. The
    walkers' draws are matched to them by their rank among the walkers (``slot``). ``free[m]`` and ``planned[m]``:
    whether mover ``m``'s path is clear of obstacles, and where it would end.
    """
    big = radius.max()
    w = 0
    for m in range(movers.shape[0]):
        slot[m] = w
        if state[movers[m]] == _EXPLORE:
            w += 1
    for m in prange(movers.shape[0]):
        i = movers[m]
        sense_one(blocked, clear, ox, oy, res, xy, heading, radius, big, i, angles, sensor_range, s_indptr,
                  s_indices, s_dist, sense_bodies, scans[m])
        length[m] = decide_one(i, slot[m], state, heading, xy, max_speed, refused, normal, uniform, turn_sigma,
                               scans[m], angles, sensor_range, goal, anchors, last_to_goal, blocked_steps, give_up,
                               min_progress, r_eff, dt)
        free[m], planned[m, 0], planned[m, 1] = plan_one(blocked, clear, ox, oy, res, xy[i, 0], xy[i, 1],
                                                         heading[i], length[m], radius[i])


@njit(cache=True)
def commit_moves(movers, length, free, planned, xy, radius, state, goal, distance, refused, bodies, d_indptr,
                 d_indices, d_dist):  # pragma: no cover - numba
    """The moves of :func:`sense_steer_plan_threaded`'s movers, one after another, against the bodies as they stand."""
    near = 2.0 * radius.max() + 2.0 * _longest(length, movers.shape[0])
    refused[:] = False
    for m in range(movers.shape[0]):
        i = movers[m]
        if free[m]:
            r, travelled = commit_one(i, xy[i, 0], xy[i, 1], planned[m, 0], planned[m, 1], xy, radius, bodies,
                                      d_indptr, d_indices, d_dist, near)
        else:
            r, travelled = True, 0.0
        refused[i] = r
        distance[i] += travelled
    _arrive(movers, state, xy, goal)


@njit(cache=True)
def spreading_stretch(limit, grid, robots, track, draws, steer, radio, csr, watch):  # pragma: no cover - numba
    """Up to ``limit`` steps of a self-spreading loop; ``(steps done, how it ended, indptr, indices, dist)``.

    The tuples hold :func:`track_explorers`'s, the draws' and
    :func:`sense_steer_drive`'s arguments as :class:`~amronet.algorithms.self_spreading.fast.
    CompiledSpreading` passes them, the radio's search (reach, group ids, groups), this step's neighbour table and the
    books (:func:`~amronet.algorithms.common.swarm_stretch_kernels.settling_changed`'s arguments). The bodies the rings
    and the moves meet are the table's (the caller
    checked that they reach no farther) or, for the moves without collisions, none.
    """
    blocked, clear, ox, oy, res = grid
    xy, heading, state, status, max_speed, radius, distance = robots
    current, deployed, is_ref, want_other, r_eff, r_c, local, disabled, explorers, new_current, nearest, other, \
        movers, walkers = track
    bitgens, starts, normal, uniform = draws
    refused, turn_sigma, angles, sensor_range, sense_bodies, goal, anchors, last_to_goal, blocked_steps, give_up, \
        min_progress, dt, drive_bodies, none_indptr, none_indices, none_dist, scans, length = steer
    indptr, indices, dist = csr
    for s in range(limit):
        _, candidates, n_movers, n_walkers = track_explorers(
            state, status, current, deployed, is_ref, indptr, indices, dist, want_other, r_eff, xy, r_c, local,
            disabled, explorers, new_current, nearest, other, movers, walkers)
        if candidates:
            return s, CANDIDATES, indptr, indices, dist
        if n_movers == 0:
            refused[:] = False
        else:
            if not draw_normal_uniform(bitgens, starts, walkers[:n_walkers], normal, uniform):
                return s, BAD_DRAW, indptr, indices, dist
            if drive_bodies:
                d_indptr, d_indices, d_dist = indptr, indices, dist
            else:
                d_indptr, d_indices, d_dist = none_indptr, none_indices, none_dist
            sense_steer_drive(blocked, clear, ox, oy, res, xy, heading, state, max_speed, radius, distance, refused,
                              movers[:n_movers], normal[:n_walkers], uniform[:n_walkers], turn_sigma, angles,
                              sensor_range, indptr, indices, dist, sense_bodies, goal, anchors, last_to_goal,
                              blocked_steps, give_up, min_progress, r_eff, dt, drive_bodies, d_indptr, d_indices,
                              d_dist, scans, length)
        how, indptr, indices, dist = after_step(xy, state, radio, watch)
        if how != QUIET:
            return s + 1, how, indptr, indices, dist
    return limit, QUIET, indptr, indices, dist
