"""The kernels of the compiled steps (:mod:`amronet.sim.compiled_step`): sense, decide and move in compiled passes.

Each calls, robot by robot and in the reference's order, the same compiled functions the phase-by-phase path
calls (range rings, reference tracking, random walk, go-to-goal, forces, drive), so the result is the same bit for
bit. Kept apart from the Python that drives them so that the kernel cache's key (:mod:`amronet.kernel_cache`)
covers only what the kernels read.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit, prange

from amronet.algorithms.agent_assisted import track_agents
from amronet.algorithms.explorers.frontier.knowledge import FREE_FLOOR, HIT_GAIN, OCCUPIED_CAP, integrate_readings
from amronet.algorithms.forces import inverse_square_one
from amronet.algorithms.goto import steer_one
from amronet.algorithms.potential_field import come_to_rest, wake_and_accelerate
from amronet.algorithms.references import track_row
from amronet.engine.motion import commit_one, drive_one, plan_one, walk_one
from amronet.engine.robots import State
from amronet.engine.sensing import cast_bodies_one, cast_grid_one

__all__ = [
    "commit_moves",
    "drive_movers",
    "field_step",
    "list_movers",
    "sense_steer_drive",
    "sense_steer_plan_threaded",
    "sense_track_agents",
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
    :func:`~amronet.algorithms.triangular.select_triangles` that need no graph already rule its triangle out: its
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
def field_step(blocked, clear, ox, oy, res, routers, state, xy, heading, max_speed, radius, distance, indptr, indices,
               dist, sense, angles, sensor_range, s_indptr, s_indices, s_dist, sense_bodies, k_obstacle, cap,
               obstacle_force, scan, velocity, rest_count, window_start, force, held_force, k_cover, k_degree, q_rc,
               k_conn, damping, mass, dt, rest_fraction, wakeups, rest_steps, bodies, d_indptr, d_indices, d_dist,
               movers, speed, refused):  # pragma: no cover - numba
    """Sense, decide and move the potential-field routers: the reference's kernels and per-robot functions in order."""
    if sense:  # the exploring routers' rings and the obstacles' push (resting routers keep their last one)
        big = radius.max()
        for i in routers:
            if state[i] != _EXPLORE:
                continue
            cast_grid_one(blocked, clear, ox, oy, res, xy[i, 0], xy[i, 1], heading[i], angles, sensor_range, scan)
            if sense_bodies:
                cast_bodies_one(i, s_indptr, s_indices, s_dist, xy, heading[i], angles, sensor_range, radius, big,
                                scan)
            obstacle_force[i, 0], obstacle_force[i, 1] = inverse_square_one(scan, heading[i], angles, sensor_range,
                                                                            k_obstacle, cap)
    n = wake_and_accelerate(routers, state, indptr, indices, dist, xy, obstacle_force, velocity, heading, max_speed,
                            rest_count, window_start, force, held_force, k_cover, k_degree, q_rc, cap, k_conn,
                            damping, mass, dt, rest_fraction, _EXPLORE, _REFERENCE, wakeups, movers, speed)
    if n == 0:
        return
    longest = 0.0
    for m in range(n):
        length = speed[m] * dt
        if m == 0 or length > longest:
            longest = length
    near = 2.0 * radius.max() + 2.0 * longest
    for m in range(n):
        i = movers[m]
        refused[m], travelled = drive_one(blocked, clear, ox, oy, res, i, heading[i], speed[m] * dt, xy, radius,
                                          bodies, d_indptr, d_indices, d_dist, near)
        distance[i] += travelled
    come_to_rest(movers[:n], refused[:n], state, xy, max_speed, velocity, rest_count, window_start, force,
                 held_force, rest_steps, dt, rest_fraction, damping, _REFERENCE)


@njit(cache=True)
def sense_track_agents(blocked, clear, ox, oy, res, xy, heading, radius, agents, angles, sensor_range, s_indptr,
                       s_indices, s_dist, sense_bodies, scans, current, is_ref, status, indptr, indices, dist,
                       want_other, left, r_eff, nearest, other, integrate, score, seen, g_ox, g_oy, g_res, nodes,
                       robot_r, buf_r, buf_c, row_stamp, stamp):  # pragma: no cover - numba
    """The agents' rings, their reference tracking and, when none of them must act, their rings in the shared grid.

    What the sense phase (:func:`~amronet.engine.sensing.range_scan`), the start of
    :meth:`~amronet.algorithms.agent_assisted.AgentAssisted.decide` (:func:`track_agents`) and (with ``integrate``)
    the frontier explorer's :meth:`~amronet.algorithms.explorers.frontier.knowledge.KnowledgeGrid.integrate` do for
    the agents, with the same functions on the same numbers.

    Returns:
        ``(triangle candidates, losing)`` as :func:`track_agents` counts them; the grid is left alone unless both
        are 0.
    """
    big = radius.max()
    n = agents.shape[0]
    for m in range(n):
        i = agents[m]
        cast_grid_one(blocked, clear, ox, oy, res, xy[i, 0], xy[i, 1], heading[i], angles, sensor_range, scans[m])
    if sense_bodies:
        for m in range(n):
            i = agents[m]
            cast_bodies_one(i, s_indptr, s_indices, s_dist, xy, heading[i], angles, sensor_range, radius, big,
                            scans[m])
    n_cand, n_losing = track_agents(agents, current, is_ref, status, indptr, indices, dist, want_other, left, r_eff,
                                    nearest, other)
    if n_cand or n_losing or not integrate:
        return n_cand, n_losing
    integrate_agents(xy, heading, agents, angles, sensor_range, scans, score, seen, g_ox, g_oy, g_res, nodes, robot_r,
                     buf_r, buf_c, row_stamp, stamp)
    return 0, 0


@njit(cache=True)
def integrate_agents(xy, heading, agents, angles, sensor_range, scans, score, seen, g_ox, g_oy, g_res, nodes, robot_r,
                     buf_r, buf_c, row_stamp, stamp):  # pragma: no cover - numba
    """The agents' readings in the frontier explorer's shared grid, as its ``KnowledgeGrid.integrate`` puts them."""
    n = agents.shape[0]
    pos = np.empty((n, 2))
    facing = np.empty(n)
    for m in range(n):
        i = agents[m]
        pos[m, 0] = xy[i, 0]
        pos[m, 1] = xy[i, 1]
        facing[m] = heading[i]
    integrate_readings(score, seen, g_ox, g_oy, g_res, pos, facing, scans, angles, sensor_range, nodes, robot_r,
                       np.int64(HIT_GAIN), np.int64(OCCUPIED_CAP), np.int64(FREE_FLOOR), buf_r, buf_c, row_stamp, stamp)


@njit(cache=True)
def drive_movers(blocked, clear, ox, oy, res, movers, length, xy, heading, radius, bodies, indptr, indices, dist,
                 near, distance, refused):  # pragma: no cover - numba
    """The move phase of :func:`amronet.sim.phases.move` for ``movers`` (each by ``length[m]``), one after another.

    ``refused`` ``(N,)`` is set for every robot: the movers' refusals, ``False`` for the rest (what the agent
    controller's ``after_move`` keeps).
    """
    refused[:] = False
    for m in range(movers.shape[0]):
        i = movers[m]
        r, travelled = drive_one(blocked, clear, ox, oy, res, i, heading[i], length[m], xy, radius, bodies, indptr,
                                 indices, dist, near)
        refused[i] = r
        distance[i] += travelled
