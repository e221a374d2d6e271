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
from amronet.algorithms.common.references import track_state_rows
from amronet.algorithms.common.swarm_stretch_kernels import BAD_DRAW, CANDIDATES, QUIET, after_step_skin
from amronet.algorithms.self_spreading.kernel_data import Draws
from amronet.algorithms.self_spreading.step_passes import arrive, drive_movers, sense_movers
from amronet.algorithms.self_spreading.triangle_kernels import settle_with_triangles
from amronet.algorithms.self_spreading.walk_kernels import (
    GROWTH,
    RANDOM,
    growth_field_kernel,
    random_heading,
    walk_heading,
)
from amronet.engine.bitgen import draw_normal_uniform
from amronet.engine.kernel_data import Csr
from amronet.engine.motion import commit_one, plan_one
from amronet.engine.robots import State
from amronet.engine.sensing import cast_bodies_one, cast_grid_one
from amronet.engine.skin_table import no_skin

__all__ = [
    "commit_moves",
    "list_movers",
    "sense_steer_drive",
    "sense_steer_drive_rules",
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
    """The routers that move this step (exploring or on their way to a triangle goal), and the walkers among them.

    Their counts ``(m, w)``; listed without a branch (``movers`` and ``walkers`` ``(N,)``: past the counts they
    hold scratch).
    """
    if movers.shape[0] < state.shape[0] or walkers.shape[0] < state.shape[0]:
        raise ValueError("list_movers: movers and walkers must hold a slot per robot")
    m = 0
    w = 0
    for i in range(state.shape[0]):
        s = state[i]
        walking = s == _EXPLORE
        movers[m] = i
        m += walking | (s == _TRIANGLE)
        walkers[w] = i
        w += walking
    return m, w


@njit(cache=True)
def track_explorers(data, indptr, indices, dist):  # pragma: no cover - numba
    """Reference tracking of every exploring router from the table's rows; the stops too when no triangle may start.

    A router that met a reference of another status is a *candidate* unless the rules of
    :func:`~amronet.algorithms.common.triangular.select_triangles` that need no graph already rule its triangle out: its
    two references are within ``r_c`` of each other, or (``local``) both are disabled.

    Returns:
        ``(k, candidates, n_movers, n_walkers)``: the number of explorers (their ids, new references, nearest
        reference distances and references of another status in the first ``k`` entries of ``data.tracked``) and
        how many are candidates. With candidates nothing is changed (the caller settles the explorers and lists
        the movers); without, the routers that move on (:func:`list_movers`) are listed too.
    """
    robots, tracking, tracked = data.robots, data.tracking, data.tracked
    state, status, xy = robots.state, robots.status, robots.xy
    current, is_ref, disabled = tracking.current, tracking.is_ref, tracking.disabled
    explorers, new_current, nearest, other = tracked.explorers, tracked.new_current, tracked.nearest, tracked.other
    n = state.shape[0]
    for j in range(n):
        is_ref[j] = tracking.deployed[state[j]]
    k = track_state_rows(state, np.int64(_EXPLORE), current, is_ref, status, indptr, indices, dist, tracking.want_other,
                         (explorers, new_current, nearest, other))
    candidates = 0
    for m in range(k):
        c = new_current[m]
        o = other[m]
        if o >= 0:
            dx = xy[c, 0] - xy[o, 0]
            dy = xy[c, 1] - xy[o, 1]
            if math.sqrt(dx * dx + dy * dy) > tracking.r_c and not (tracking.local and disabled[c] and disabled[o]):
                candidates += 1
    if candidates:
        return k, candidates, 0, 0
    for m in range(k):
        i = explorers[m]
        c = new_current[m]
        current[i] = c
        if tracking.by_signal:
            losing = _weak_link(i, -nearest[m], tracking)
        else:
            losing = nearest[m] >= tracking.r_eff
        if c >= 0 and losing:
            state[i] = _REFERENCE
            status[i] = status[c]
    n_movers, n_walkers = list_movers(state, tracked.movers, tracked.walkers)
    return k, 0, n_movers, n_walkers


@njit(cache=True, inline="always")
def _weak_link(i, best, tracking):  # pragma: no cover - numba
    """The ``link-quality`` stop rule of explorer ``i`` with best reference margin ``best`` (``-inf``: none heard).

    Its moving average is updated as :meth:`~amronet.algorithms.common.link_quality.MarginSmoother.update` updates it
    (restarted, ``nan``, when nothing is heard); it stops below ``stop_margin_db`` smoothed or ``loss_margin_db`` raw.
    """
    smoothed = tracking.smoothed
    old = smoothed[i]
    new = best if np.isnan(old) else old + tracking.alpha * (best - old)
    if not np.isfinite(best):
        new = np.nan
    smoothed[i] = new
    return new < tracking.stop_margin_db or best < tracking.loss_margin_db


@njit(cache=True, inline="always")
def sense_one(grid, robots, big, i, ring, s_csr, sense_bodies, out):  # pragma: no cover - numba
    """Robot ``i``'s ring into ``out``: the grid's beams, then (``sense_bodies``) shortened by the bodies near it."""
    xy, heading = robots.xy, robots.heading
    cast_grid_one(grid.blocked, grid.clear, grid.ox, grid.oy, grid.res, xy[i, 0], xy[i, 1], heading[i], ring.angles,
                  ring.sensor_range, out)
    if sense_bodies:
        cast_bodies_one(i, s_csr.indptr, s_csr.indices, s_csr.dist, xy, heading[i], ring.angles, ring.sensor_range,
                        robots.radius, big, out)


@njit(cache=True)
def decide_one(i, w, robots, refused, turn_sigma, draws, scan, ring, steering, r_eff, dt):  # pragma: no cover
    """Mover ``i``'s decision from its ring ``scan`` under the paper's random walk, and the length of its step.

    A walker (the ``w``-th) walks (``refused``, ``turn_sigma``: the
    :class:`~amronet.algorithms.self_spreading.kernel_data.Walk`'s; not the whole named tuple, which the call would
    copy field by field for every mover), a triangle router steers to its goal (and settles when it cannot go on): the
    operations of :func:`sense_steer_drive`'s decide loop, which keeps them (and its
    sense loop) written out: calling this function and :func:`sense_one` from there made the one-thread step 15-20 %
    slower at N = 3 000. Not inlined: in a ``prange`` loop numba 0.68 loses what is written into an array reached
    through a named tuple's field (``robots.heading[i] = ...``) in the loop's own body, inlined code included; a
    called function keeps it. :func:`decide_one_rules` takes the other walk rules.
    """
    if robots.state[i] == _EXPLORE:
        robots.heading[i] = random_heading(robots.heading[i], scan, ring, refused[i], draws.normal[w],
                                           draws.uniform[w], turn_sigma)
        return robots.max_speed[i] * dt
    return _steer_step(i, robots, steering, scan, ring, r_eff, dt)


@njit(cache=True)
def decide_one_rules(i, w, robots, walk, draws, scan, ring, steering, r_eff, dt, table):  # pragma: no cover - numba
    """:func:`decide_one` under the walk rule ``walk.rule``, whichever it is (``table``: the step's neighbours)."""
    if robots.state[i] == _EXPLORE:
        robots.heading[i] = walk_heading(i, robots.heading, scan, ring, walk.refused[i], draws.normal[w],
                                         draws.uniform[w], walk, robots.xy, table, walk.rule)
        return robots.max_speed[i] * dt
    return _steer_step(i, robots, steering, scan, ring, r_eff, dt)


@njit(cache=True, inline="always")
def _steer_step(i, robots, steering, scan, ring, r_eff, dt):  # pragma: no cover - numba
    """Triangle router ``i``'s go-to-goal step (it settles when it cannot go on): the length of its step."""
    step, done = steer_one(i, robots.xy, robots.heading, steering, scan, ring.angles, ring.sensor_range,
                           robots.max_speed[i] * dt, r_eff)
    if done:
        robots.state[i] = _TRIANGLE_SETTLED
    speed = step / dt
    return speed * dt


@njit(cache=True)
def sense_steer_drive(data, n_movers, normal, uniform, s_indptr, s_indices, s_dist, d_indptr, d_indices,
                      d_dist):  # pragma: no cover - numba
    """Sense, steer and drive the ``n_movers`` movers under the paper's random walk (:data:`RANDOM`).

    The reference's per-robot functions, in the same order. ``normal`` and ``uniform``: the walkers' draws
    (:func:`~amronet.engine.streams.normal_then_uniform`), scaled here as the walk rule scales them
    (:func:`~amronet.algorithms.self_spreading.walk_kernels.walk_heading`: the same operations on the same numbers).
    With more than one robot the rings meet the bodies of the neighbour list ``s_indptr, s_indices, s_dist``, and
    (with collisions) the moves those of ``d_indptr, d_indices, d_dist``: this step's lists come as arrays, not as
    :class:`~amronet.engine.kernel_data.Csr` s (numba types a named tuple field by field at every call from Python, and
    three of them would cost more than all the arrays they hold). The rings and the moves are
    :mod:`~amronet.algorithms.self_spreading.step_passes`'; the decide loop between them is written for the random
    walk alone (no branch on the rule per walker, none of the other rules' code); the other walk rules take
    :func:`sense_steer_drive_rules`.
    """
    robots, steering, walk, ring = data.robots, data.steering, data.walk, data.ring
    xy, heading, state, max_speed = robots.xy, robots.heading, robots.state, robots.max_speed
    scans, length, refused, turn_sigma = data.moves.scans, data.moves.length, walk.refused, walk.turn_sigma
    r_eff, dt = data.tracking.r_eff, data.dt
    movers = data.tracked.movers[:n_movers]
    big, close = sense_movers(data, n_movers, s_indptr, s_indices, s_dist)
    w = 0
    longest = 0.0
    for m in range(movers.shape[0]):  # decide: walkers walk, triangle routers steer to their goals
        i = movers[m]
        if state[i] == _EXPLORE:
            heading[i] = random_heading(heading[i], scans[m], ring, refused[i], normal[w], uniform[w], turn_sigma)
            w += 1
            speed = max_speed[i]
        else:
            step, done = steer_one(i, xy, heading, steering, scans[m], ring.angles, ring.sensor_range,
                                   max_speed[i] * dt, r_eff)
            if done:
                state[i] = _TRIANGLE_SETTLED
            speed = step / dt
        length[m] = speed * dt
        if m == 0 or length[m] > longest:
            longest = length[m]
    drive_movers(data, n_movers, big, longest, s_indptr, s_indices, s_dist, d_indptr, d_indices, d_dist, close)


@njit(cache=True)
def sense_steer_drive_rules(data, n_movers, normal, uniform, s_indptr, s_indices, s_dist, d_indptr, d_indices, d_dist,
                            table, t):  # pragma: no cover - numba
    """:func:`sense_steer_drive` under the walk rule ``data.walk.rule``, whichever it is.

    ``table``: the step's neighbour table as a plain ``(indptr, indices, dist)``, and ``t`` the step's time (the
    growth walks' field, :func:`~amronet.algorithms.self_spreading.walk_kernels.growth_field_kernel`, computed first).
    """
    rows = Csr(table[0], table[1], table[2])
    robots, steering, walk, ring = data.robots, data.steering, data.walk, data.ring
    xy, heading, state, max_speed = robots.xy, robots.heading, robots.state, robots.max_speed
    scans, length, refused, rule = data.moves.scans, data.moves.length, walk.refused, walk.rule
    r_eff, dt = data.tracking.r_eff, data.dt
    movers = data.tracked.movers[:n_movers]
    if rule >= GROWTH:
        growth_field_kernel(walk, data.tracking.deployed, state, rows.indptr, rows.indices, t)
    big, close = sense_movers(data, n_movers, s_indptr, s_indices, s_dist)
    w = 0
    longest = 0.0
    for m in range(movers.shape[0]):  # decide, as sense_steer_drive does under the rule
        i = movers[m]
        if state[i] == _EXPLORE:
            heading[i] = walk_heading(i, heading, scans[m], ring, refused[i], normal[w], uniform[w], walk, xy, rows,
                                      rule)
            w += 1
            speed = max_speed[i]
        else:
            step, done = steer_one(i, xy, heading, steering, scans[m], ring.angles, ring.sensor_range,
                                   max_speed[i] * dt, r_eff)
            if done:
                state[i] = _TRIANGLE_SETTLED
            speed = step / dt
        length[m] = speed * dt
        if m == 0 or length[m] > longest:
            longest = length[m]
    drive_movers(data, n_movers, big, longest, s_indptr, s_indices, s_dist, d_indptr, d_indices, d_dist, close)


@njit(cache=True, inline="always")
def _longest(length, n):  # pragma: no cover - numba
    longest = 0.0
    for m in range(n):
        if m == 0 or length[m] > longest:
            longest = length[m]
    return longest


@njit(cache=True)
def sense_steer_plan_threaded(data, n_movers, normal, uniform, s_indptr, s_indices, s_dist, table,
                              t):  # pragma: no cover - numba
    """:func:`sense_steer_drive` up to the moves' obstacle checks, on several threads; :func:`commit_moves` ends it.

    Every mover's ring, decision and path against the map depend on where the robots stand before anybody moves and
    on the mover's own state, nothing else, so each mover is done in one go by one thread: the same numbers. The
    walkers' draws are matched to them by their rank among the walkers (``moves.slot``). ``moves.free[m]`` and
    ``moves.planned[m]``: whether mover ``m``'s path is clear of obstacles, and where it would end. ``table`` and
    ``t``: as :func:`sense_steer_drive_rules` takes them (the growth field is computed first, on this thread).
    """
    rows = Csr(table[0], table[1], table[2])
    if data.walk.rule >= GROWTH:
        growth_field_kernel(data.walk, data.tracking.deployed, data.robots.state, rows.indptr, rows.indices, t)
    _plan_threaded(data.grid, data.robots, data.walk, Draws(normal, uniform), data.steering, data.ring,
                   Csr(s_indptr, s_indices, s_dist), data.tracked.movers[:n_movers], data.moves, data.tracking.r_eff,
                   data.dt, rows)


@njit(cache=True, parallel=True)
def _plan_threaded(grid, robots, walk, draws, steering, ring, s_csr, movers, moves, r_eff, dt,
                   rows):  # pragma: no cover - numba
    """:func:`sense_steer_plan_threaded`'s threads.

    numba's ``prange`` takes flat named tuples, not nested ones, and loses what its body writes into an array reached
    through a named tuple's field: the arrays written here are taken out first, :func:`decide_one` is a call.
    """
    scans, length, slot, free, planned, _ = moves
    big = robots.radius.max()
    sense_bodies = robots.xy.shape[0] > 1
    random = walk.rule == RANDOM  # the paper's walk: the call compiled for it alone
    w = 0
    for m in range(movers.shape[0]):
        slot[m] = w
        if robots.state[movers[m]] == _EXPLORE:
            w += 1
    for m in prange(movers.shape[0]):
        i = movers[m]
        sense_one(grid, robots, big, i, ring, s_csr, sense_bodies, scans[m])
        if random:
            length[m] = decide_one(i, slot[m], robots, walk.refused, walk.turn_sigma, draws, scans[m], ring, steering,
                                   r_eff, dt)
        else:
            length[m] = decide_one_rules(i, slot[m], robots, walk, draws, scans[m], ring, steering, r_eff, dt, rows)
        free[m], planned[m, 0], planned[m, 1] = plan_one(grid.blocked, grid.clear, grid.ox, grid.oy, grid.res,
                                                         robots.xy[i, 0], robots.xy[i, 1], robots.heading[i],
                                                         length[m], robots.radius[i])


@njit(cache=True)
def commit_moves(data, n_movers, d_indptr, d_indices, d_dist, drive_bodies):  # pragma: no cover - numba
    """The moves of :func:`sense_steer_plan_threaded`'s movers, one after another, against the bodies as they stand."""
    robots, moves, refused = data.robots, data.moves, data.walk.refused
    xy, radius, state, distance = robots.xy, robots.radius, robots.state, robots.distance
    length, free, planned = moves.length, moves.free, moves.planned
    movers = data.tracked.movers[:n_movers]
    near = 2.0 * radius.max() + 2.0 * _longest(length, movers.shape[0])
    refused[:] = False
    for m in range(movers.shape[0]):
        i = movers[m]
        if free[m]:
            r, travelled = commit_one(i, xy[i, 0], xy[i, 1], planned[m, 0], planned[m, 1], xy, radius, drive_bodies,
                                      d_indptr, d_indices, d_dist, near)
        else:
            r, travelled = True, 0.0
        refused[i] = r
        distance[i] += travelled
    arrive(movers, state, xy, data.steering.goal)


@njit(cache=True)
def spreading_stretch(limit, data, streams, radio, csr, books, index):  # pragma: no cover - numba
    """Up to ``limit`` steps of a self-spreading loop from the table ``csr``; ``(steps done, how it ended, table)``.

    ``index``: the first step's index (step ``s`` of the stretch is at ``(index + s) * dt`` seconds, the loop's
    clock); ``streams``: the walkers' generators; ``radio`` and ``books``: the radio's search and the runs' books
    (:func:`~amronet.algorithms.common.swarm_stretch_kernels.after_step_skin`: the table through a skin). The bodies
    the rings and the moves meet are the table's (the caller checked that they reach no farther) or none.
    """
    robots, tracked, draws = data.robots, data.tracked, data.draws
    skin = no_skin()
    for s in range(limit):
        k, candidates, n_movers, n_walkers = track_explorers(data, csr.indptr, csr.indices, csr.dist)
        if candidates and not data.tracking.starts:
            return s, CANDIDATES, csr
        if candidates:  # the none and local rules: the controller's choices, compiled
            settle_with_triangles(data, k)
            n_movers, n_walkers = list_movers(robots.state, tracked.movers, tracked.walkers)
        if n_movers == 0:
            data.walk.refused[:] = False
        else:
            walkers = tracked.walkers[:n_walkers]
            if not draw_normal_uniform(streams.bitgens, streams.starts, walkers, draws.normal, draws.uniform):
                return s, BAD_DRAW, csr
            d_csr = csr if data.collisions else data.no_bodies
            normal, uniform = draws.normal[:n_walkers], draws.uniform[:n_walkers]
            if data.walk.rule == RANDOM:
                sense_steer_drive(data, n_movers, normal, uniform, csr.indptr, csr.indices, csr.dist, d_csr.indptr,
                                  d_csr.indices, d_csr.dist)
            else:
                sense_steer_drive_rules(data, n_movers, normal, uniform, csr.indptr, csr.indices, csr.dist,
                                        d_csr.indptr, d_csr.indices, d_csr.dist, (csr.indptr, csr.indices, csr.dist),
                                        (index + s) * data.dt)
        how, csr, skin = after_step_skin(robots.xy, robots.state, radio, books, skin, limit - s > 2)
        if how != QUIET:
            return s + 1, how, csr
    return limit, QUIET, csr
