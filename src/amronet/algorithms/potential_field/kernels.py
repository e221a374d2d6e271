"""The kernel of the potential field's fast step (:mod:`amronet.algorithms.potential_field.fast`).

The rings, obstacle forces, the controller's wake-and-accelerate, the moves and the come-to-rest rule in one
pass, each the same compiled function the phase-by-phase path calls, in the same order: the same result bit for bit.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from amronet.algorithms.common.forces import constrained_coverage_force, inverse_square_one
from amronet.algorithms.common.swarm_stretch_kernels import QUIET, after_step
from amronet.engine.motion import drive_one
from amronet.engine.robots import State
from amronet.engine.sensing import cast_bodies_one, cast_grid_one

__all__ = ["come_to_rest", "field_step", "field_stretch", "wake_and_accelerate"]

_EXPLORE = State.EXPLORE
_REFERENCE = State.REFERENCE
_TRIANGLE = State.TRIANGLE
_TRIANGLE_SETTLED = State.TRIANGLE_SETTLED



@njit(cache=True)
def wake_and_accelerate(routers, state, indptr, indices, dist, xy, obstacle_force, velocity, heading, max_speed,
                        rest_count, window_start, force, held_force, k_cover, k_degree, q_rc, cap,
                        k_conn, damping, mass, dt, rest_fraction, explore, reference, wakeups, movers,
                        speed):  # pragma: no cover - numba
    """Wake resting routers whose force left the held one, then accelerate every moving router; the mover count.

    A router's force depends only on positions and the neighbour table, so one pass in router order gives the
    same result as waking everybody first and then moving everybody.
    """
    n_movers = 0
    for i in routers:
        if state[i] != explore and state[i] != reference:
            continue
        fx, fy = constrained_coverage_force(i, indptr, indices, dist, xy, k_cover, k_degree, q_rc, cap, k_conn)
        fx += obstacle_force[i, 0]
        fy += obstacle_force[i, 1]
        if state[i] == reference:
            change = np.hypot(fx - held_force[i, 0], fy - held_force[i, 1])
            if change <= damping * 2.0 * rest_fraction * max_speed[i]:
                continue
            state[i] = explore
            rest_count[i] = 0
            window_start[i, 0] = xy[i, 0]
            window_start[i, 1] = xy[i, 1]
            wakeups[i] += 1
        force[i, 0] = fx
        force[i, 1] = fy
        vx = velocity[i, 0] + (fx - damping * velocity[i, 0]) / mass * dt
        vy = velocity[i, 1] + (fy - damping * velocity[i, 1]) / mass * dt
        scale = min(1.0, max_speed[i] / max(np.hypot(vx, vy), 1e-300))
        vx *= scale
        vy *= scale
        velocity[i, 0] = vx
        velocity[i, 1] = vy
        s = np.hypot(vx, vy)
        if s > 0.0:
            heading[i] = np.arctan2(vy, vx)
        movers[n_movers] = i
        speed[n_movers] = s
        n_movers += 1
    return n_movers


@njit(cache=True)
def come_to_rest(movers, refused, state, xy, max_speed, velocity, rest_count, window_start, force, held_force,
                 rest_steps, dt, rest_fraction, damping, reference):  # pragma: no cover - numba
    """The rest rule after a move (see the module docstring)."""
    window = rest_steps * dt
    for m in range(len(movers)):
        i = movers[m]
        if refused[m]:
            velocity[i, 0] = 0.0
            velocity[i, 1] = 0.0
        rest_count[i] += 1
        if rest_count[i] < rest_steps:
            continue
        v_rest = rest_fraction * max_speed[i]
        drift = np.hypot(xy[i, 0] - window_start[i, 0], xy[i, 1] - window_start[i, 1])
        calm = np.hypot(force[i, 0], force[i, 1]) <= damping * 2.0 * v_rest
        if drift < v_rest * window and (calm or refused[m]):
            state[i] = reference
            velocity[i, 0] = 0.0
            velocity[i, 1] = 0.0
            # it rests under the force it feels now: about none, or the push a wall takes up; it wakes up when
            # that force changes
            held_force[i, 0] = force[i, 0]
            held_force[i, 1] = force[i, 1]
        else:
            rest_count[i] = 0
            window_start[i, 0] = xy[i, 0]
            window_start[i, 1] = xy[i, 1]


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
def field_stretch(limit, head, ring, tail, sense_table, drive_table, radio, csr, watch):  # pragma: no cover - numba
    """Up to ``limit`` steps of a potential-field loop; ``(steps done, how it ended, indptr, indices, dist)``.

    :func:`field_step`'s arguments as :class:`~amronet.algorithms.potential_field.fast.CompiledField`
    passes them but the neighbour tables: ``head`` (the map's grid to the distances), ``ring`` (beam angles, sensor
    range) and ``tail`` (an empty neighbour list, then the arguments from ``sense`` on); the bodies the rings and the
    moves meet are the table's when ``sense_table`` / ``drive_table``, else the empty list. Then the radio's search,
    the table and the books as for :func:`spreading_stretch`.
    """
    none_indptr, none_indices, none_dist, sense, sense_bodies, k_obstacle, cap, obstacle_force, scan, velocity, \
        rest_count, window_start, force, held_force, k_cover, k_degree, q_rc, k_conn, damping, mass, dt, \
        rest_fraction, wakeups, rest_steps, bodies, movers, speed, refused = tail
    blocked, clear, ox, oy, res, routers, state, xy, heading, max_speed, radius, distance = head
    angles, sensor_range = ring
    indptr, indices, dist = csr
    for s in range(limit):
        if sense_table:
            s_indptr, s_indices, s_dist = indptr, indices, dist
        else:
            s_indptr, s_indices, s_dist = none_indptr, none_indices, none_dist
        if drive_table:
            d_indptr, d_indices, d_dist = indptr, indices, dist
        else:
            d_indptr, d_indices, d_dist = none_indptr, none_indices, none_dist
        field_step(blocked, clear, ox, oy, res, routers, state, xy, heading, max_speed, radius, distance, indptr,
                   indices, dist, sense, angles, sensor_range, s_indptr, s_indices, s_dist, sense_bodies, k_obstacle,
                   cap, obstacle_force, scan, velocity, rest_count, window_start, force, held_force, k_cover,
                   k_degree, q_rc, k_conn, damping, mass, dt, rest_fraction, wakeups, rest_steps, bodies, d_indptr,
                   d_indices, d_dist, movers, speed, refused)
        how, indptr, indices, dist = after_step(xy, state, radio, watch)
        if how != QUIET:
            return s + 1, how, indptr, indices, dist
    return limit, QUIET, indptr, indices, dist
