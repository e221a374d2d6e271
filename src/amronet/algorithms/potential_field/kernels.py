"""The kernel of the potential field's fast step (:mod:`amronet.algorithms.potential_field.fast`).

The rings, obstacle forces, the controller's wake-and-accelerate, the moves and the come-to-rest rule in one
pass, each the same compiled function the phase-by-phase path calls, in the same order: the same result bit for bit.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from amronet.algorithms.common.forces import constrained_coverage_force, inverse_square_one
from amronet.algorithms.common.swarm_stretch_kernels import QUIET, after_step
from amronet.engine.kernel_data import Csr
from amronet.engine.motion import drive_one
from amronet.engine.robots import State
from amronet.engine.sensing import cast_bodies_one, cast_grid_one

__all__ = ["come_to_rest", "field_step", "field_stretch", "wake_and_accelerate"]

_EXPLORE = State.EXPLORE
_REFERENCE = State.REFERENCE



@njit(cache=True)
def wake_and_accelerate(routers, robots, csr, field, constants, explore, reference, movers,
                        speed):  # pragma: no cover - numba
    """Wake resting routers whose force left the held one, then accelerate every moving router; the mover count.

    The links' forces come from the neighbour table ``csr``. A router's force depends only on positions and the
    neighbour table, so one pass in router order gives the same result as waking everybody first and then moving
    everybody.
    """
    state, xy, heading, max_speed = robots.state, robots.xy, robots.heading, robots.max_speed
    obstacle_force, velocity, rest_count, window_start, force, held_force, wakeups = field
    k_cover, k_degree, q_rc, cap, k_conn = (constants.k_cover, constants.k_degree, constants.q_rc, constants.cap,
                                            constants.k_conn)
    damping, mass, dt, rest_fraction = constants.damping, constants.mass, constants.dt, constants.rest_fraction
    n_movers = 0
    for i in routers:
        if state[i] != explore and state[i] != reference:
            continue
        fx, fy = constrained_coverage_force(i, csr.indptr, csr.indices, csr.dist, xy, k_cover, k_degree, q_rc, cap,
                                            k_conn)
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
def come_to_rest(movers, refused, robots, field, constants, reference):  # pragma: no cover - numba
    """The rest rule after a move (see the module docstring)."""
    state, xy, max_speed = robots.state, robots.xy, robots.max_speed
    velocity, rest_count, window_start, force, held_force = (field.velocity, field.rest_count, field.window_start,
                                                             field.force, field.held_force)
    rest_steps, rest_fraction, damping = constants.rest_steps, constants.rest_fraction, constants.damping
    window = rest_steps * constants.dt
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
def field_step(data, indptr, indices, dist, s_indptr, s_indices, s_dist, sense_bodies, d_indptr, d_indices, d_dist,
               drive_bodies):  # pragma: no cover - numba
    """Sense, decide and move the potential-field routers: the reference's kernels and per-robot functions in order.

    ``indptr, indices, dist``: the neighbour table; the rings (``data.sense``) meet the bodies of the neighbour list
    ``s_indptr, s_indices, s_dist`` (when ``sense_bodies``), the moves those of ``d_indptr, d_indices, d_dist`` (when
    ``drive_bodies``). This step's lists come as arrays, not as :class:`~amronet.engine.kernel_data.Csr` s: see
    :func:`~amronet.algorithms.self_spreading.kernels.sense_steer_drive`.
    """
    grid, robots, routers, field, constants = data.grid, data.robots, data.routers, data.field, data.constants
    blocked, clear, ox, oy, res = grid
    state, xy, heading, radius, distance = robots.state, robots.xy, robots.heading, robots.radius, robots.distance
    angles, sensor_range = data.ring.angles, data.ring.sensor_range
    scan, movers, speed, refused = data.scratch
    obstacle_force, dt = field.obstacle_force, constants.dt
    if data.sense:  # the exploring routers' rings and the obstacles' push (resting routers keep their last one)
        big = radius.max()
        for i in routers:
            if state[i] != _EXPLORE:
                continue
            cast_grid_one(blocked, clear, ox, oy, res, xy[i, 0], xy[i, 1], heading[i], angles, sensor_range, scan)
            if sense_bodies:
                cast_bodies_one(i, s_indptr, s_indices, s_dist, xy, heading[i], angles, sensor_range, radius, big,
                                scan)
            obstacle_force[i, 0], obstacle_force[i, 1] = inverse_square_one(scan, heading[i], angles, sensor_range,
                                                                            constants.k_obstacle, constants.cap)
    n = wake_and_accelerate(routers, robots, Csr(indptr, indices, dist), field, constants, np.int64(_EXPLORE),
                            np.int64(_REFERENCE), movers, speed)
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
        refused[m], travelled = drive_one(grid, i, heading[i], speed[m] * dt, xy, radius, drive_bodies,
                                          Csr(d_indptr, d_indices, d_dist), near)
        distance[i] += travelled
    come_to_rest(movers[:n], refused[:n], robots, field, constants, np.int64(_REFERENCE))


@njit(cache=True)
def field_stretch(limit, data, radio, csr, books):  # pragma: no cover - numba
    """Up to ``limit`` steps of a potential-field loop from the table ``csr``; ``(steps done, how it ended, table)``.

    Each step is :func:`field_step` with the table's bodies for the rings (``data.sense``) and, where bodies collide,
    the moves (else an empty list); then the radio's search and the books, as for
    :func:`~amronet.algorithms.self_spreading.kernels.spreading_stretch`.
    """
    robots = data.robots
    for s in range(limit):
        s_csr = csr if data.sense else data.no_bodies
        d_csr = csr if data.collisions else data.no_bodies
        field_step(data, csr.indptr, csr.indices, csr.dist, s_csr.indptr, s_csr.indices, s_csr.dist, np.bool_(True),
                   d_csr.indptr, d_csr.indices, d_csr.dist, data.collisions)
        how, csr = after_step(robots.xy, robots.state, radio, books)
        if how != QUIET:
            return s + 1, how, csr
    return limit, QUIET, csr
