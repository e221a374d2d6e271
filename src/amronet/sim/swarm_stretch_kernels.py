"""The kernels of self-spreading and potential-field stretches: the steps between two records in one compiled call.

A step of a self-spreading or potential-field loop with a compiled step (:mod:`amronet.sim.compiled_step`) is two or
three kernels with Python in between: the compiled sense-decide-move, the radio's neighbour search, the books (did a
run settle?). :func:`spreading_stretch` and :func:`field_stretch` take up to ``limit`` such steps in a row, each with
the same kernels in the same order on the same numbers, and stop after the first step in which some active run's
settled state changed (the loop's books then see it, as after any step), or, for self-spreading, *before* a step in
which a triangular deployment may start (the controller's Python decides those; that step is left whole).
"""

from __future__ import annotations

from numba import njit

from amronet.engine.bitgen import draw_normal_uniform
from amronet.engine.neighbours import search_kernel
from amronet.sim.step_kernels import field_step, sense_steer_drive, track_explorers

__all__ = ["BAD_DRAW", "CANDIDATES", "NON_FINITE", "QUIET", "SETTLING", "field_stretch", "spreading_stretch"]

QUIET = 0
"""Every step asked for was done."""
SETTLING = 1
"""The last step done changed whether an active run is settled."""
CANDIDATES = 2
"""The step after the last one done may start a triangular deployment: nothing of it was done."""
NON_FINITE = 3
"""A robot's position became non-finite in the last step done (its radio table was not built)."""
BAD_DRAW = 4
"""The walkers were not listed in order (cannot happen: :func:`~amronet.sim.step_kernels.list_movers` lists them so);
the step after the last one done is left half done."""


@njit(cache=True)
def _settling_changed(state, lookup, eligible, groups, active, settled, counts):  # pragma: no cover - numba
    """Whether an active run's settled state (none of its eligible robots in a ``lookup`` state) is not ``settled``."""
    counts[:] = 0
    for i in range(state.shape[0]):
        if eligible[i] and lookup[state[i]]:
            counts[groups[i]] += 1
    for g in range(active.shape[0]):
        if active[g] and (counts[g] == 0) != settled[g]:
            return True
    return False


@njit(cache=True, inline="always")
def _after_step(xy, state, radio, watch):  # pragma: no cover - numba
    """The radio's next table and the books after a step: ``(how, indptr, indices, dist)``.

    ``how``: :data:`NON_FINITE` (no table), :data:`SETTLING` (an active run's settled state changed: the stretch ends
    there) or :data:`QUIET`.
    """
    reach, group_ids, n_groups = radio
    lookup, eligible, groups, active, settled, counts = watch
    ok, indptr, indices, dist = search_kernel(xy, reach, group_ids, n_groups)
    if not ok:
        return NON_FINITE, indptr, indices, dist
    if _settling_changed(state, lookup, eligible, groups, active, settled, counts):
        return SETTLING, indptr, indices, dist
    return QUIET, indptr, indices, dist


@njit(cache=True)
def spreading_stretch(limit, grid, robots, track, draws, steer, radio, csr, watch):  # pragma: no cover - numba
    """Up to ``limit`` steps of a self-spreading loop; ``(steps done, how it ended, indptr, indices, dist)``.

    The tuples hold :func:`~amronet.sim.step_kernels.track_explorers`'s, the draws' and
    :func:`~amronet.sim.step_kernels.sense_steer_drive`'s arguments as :class:`~amronet.sim.compiled_step.
    CompiledSpreading` passes them, the radio's search (reach, group ids, groups), this step's neighbour table and the
    books (:func:`_settling_changed`'s arguments). The bodies the rings and the moves meet are the table's (the caller
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
        how, indptr, indices, dist = _after_step(xy, state, radio, watch)
        if how != QUIET:
            return s + 1, how, indptr, indices, dist
    return limit, QUIET, indptr, indices, dist


@njit(cache=True)
def field_stretch(limit, head, ring, tail, sense_table, drive_table, radio, csr, watch):  # pragma: no cover - numba
    """Up to ``limit`` steps of a potential-field loop; ``(steps done, how it ended, indptr, indices, dist)``.

    :func:`~amronet.sim.step_kernels.field_step`'s arguments as :class:`~amronet.sim.compiled_step.CompiledField`
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
        how, indptr, indices, dist = _after_step(xy, state, radio, watch)
        if how != QUIET:
            return s + 1, how, indptr, indices, dist
    return limit, QUIET, indptr, indices, dist

