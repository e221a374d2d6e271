"""The walk rules' compiled parts (:mod:`amronet.algorithms.self_spreading.walks`): one walker's heading, the field.

Each rule's new heading of one walker (:func:`random_heading`, :func:`straight_one`, :func:`growth_one`, and
:func:`walk_heading`, which
picks the rule and scales the walker's two draws as :class:`~amronet.algorithms.self_spreading.walks.Walker` scales
them), and the growth field in one pass (:func:`growth_field_kernel`). The reference
(:meth:`~amronet.algorithms.self_spreading.walks.Walker.steer`) calls the same per-walker functions in a loop over the
walkers; the fast step (:mod:`amronet.algorithms.self_spreading.kernels`) calls them robot by robot in its decide
loop, so a run gives the same headings bit for bit with either step.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numba import njit

from amronet.engine.motion import walk_one

__all__ = ["CORNER_TURN", "EDGE_LEAN", "GROWTH", "GROWTH_NOISE", "GUIDED", "RANDOM", "STRAIGHT", "STRAIGHT_SPREAD",
           "EdgeFollowing", "GrowthDraws", "growth_field_kernel", "growth_one", "random_heading", "straight_one",
           "walk_heading"]

RANDOM, STRAIGHT, GROWTH, GUIDED = 0, 1, 2, 3
"""The walk rules' codes in the kernels: their places in :data:`~amronet.algorithms.self_spreading.walks.WALKS`."""

STRAIGHT_SPREAD = math.pi / 4
"""``straight``: largest extra turn, either way, off an obstacle (radians)."""
GROWTH_NOISE = 0.25
"""``growth``: heading noise as a fraction of the random walk's."""
EDGE_LEAN = 0.3
"""``growth``: how far (radians) a router following an obstacle's edge leans toward it, so as not to drift off."""
CORNER_TURN = 0.35
"""``growth``: turn per step (radians) toward the side of an edge the router has lost (rounding a corner)."""


class EdgeFollowing(NamedTuple):
    """``growth``: the routers following an obstacle's edge (the walker's arrays, changed in place)."""

    follow: np.ndarray
    """``int64 (N,)``: steps left following an obstacle's edge."""
    side: np.ndarray
    """``int64 (N,)``: the side each router keeps the obstacle it follows on."""
    steps: int
    """At most this many steps following an obstacle's edge."""


class GrowthDraws(NamedTuple):
    """``growth`` and ``guided``: a step's random numbers, walker by walker."""

    noise: np.ndarray
    """The growth walk's heading noise."""
    fresh: np.ndarray
    """Fresh uniform headings (a refused move, a random walk's fresh start)."""
    draw: np.ndarray
    """Uniforms in ``[0, 1)``: the side of an edge to follow, the turn off an obstacle."""
    walk_noise: np.ndarray
    """``guided``: the random walk's heading noise."""


@njit(cache=True, inline="always")
def _seen(heading, scans, angles, sensor_range):  # pragma: no cover - numba
    """Direction away from what the beams see (weighted by closeness); whether anything is seen; whether ahead."""
    px = 0.0
    py = 0.0
    seen = False
    ahead = False
    for k in range(scans.shape[0]):
        w = (sensor_range - scans[k]) / sensor_range
        if w <= 0.0:
            continue
        seen = True
        if math.cos(angles[k]) > 0.0:
            ahead = True
        a = heading + angles[k]
        px -= min(w, 1.0) * math.cos(a)
        py -= min(w, 1.0) * math.sin(a)
    if math.hypot(px, py) < 1e-9:
        return heading + math.pi, seen, ahead
    return math.atan2(py, px), seen, ahead


@njit(cache=True, inline="always")
def straight_one(heading, scan, angles, sensor_range, refused, fresh, draw):  # pragma: no cover - numba
    """``straight``: one walker's new heading (``fresh``: a uniform heading; ``draw``: a uniform in ``[0, 1)``)."""
    if refused:
        return fresh
    away, _, ahead = _seen(heading, scan, angles, sensor_range)
    if ahead:
        return away + STRAIGHT_SPREAD * (2.0 * draw - 1.0)
    return heading


@njit(cache=True, inline="always")
def _toward(i, want, heading, scan, angles, sensor_range, edges, draw, noise):  # pragma: no cover - numba
    """Head for ``want``; when an obstacle ahead stands in the way, follow its edge until the way is clear."""
    follow, side = edges.follow, edges.side
    away, seen, ahead = _seen(heading[i], scan, angles, sensor_range)
    if follow[i] > 0:
        follow[i] -= 1
        if follow[i] == 0:  # given up: off the obstacle at a random angle
            return away + (math.pi / 2) * (2.0 * draw - 1.0) if seen else want + noise
        if not seen:  # the edge ends (a corner, a door): round it
            return heading[i] + side[i] * CORNER_TURN
        if math.cos(want - away) > 0.2:  # the way to want leads off the obstacle
            follow[i] = 0
            return want + noise
        return away + side[i] * (math.pi / 2 - EDGE_LEAN)
    if ahead:
        if math.cos(want - away) < 0.0:  # want lies beyond the obstacle: follow its edge
            follow[i] = edges.steps
            side[i] = 1 if draw < 0.5 else -1
            return away + side[i] * (math.pi / 2 - EDGE_LEAN)
        return math.atan2(math.sin(want) + math.sin(away), math.cos(want) + math.cos(away))
    return want + noise


@njit(cache=True, inline="always")
def growth_one(i, heading, xy, field, table, r_c, scan, ring, refused, drawn, edges, diffuse):  # pragma: no cover
    """``growth`` (``diffuse`` false) or ``guided``: walker ``i``'s new heading from the growth ``field`` it hears.

    ``table``: the step's neighbour table (a :class:`~amronet.engine.kernel_data.Csr`); ``ring``: the walkers'
    :class:`~amronet.algorithms.common.swarm_data.Ring`; ``drawn``: its numbers, a :class:`GrowthDraws` of scalars.
    ``edges`` is changed in place.
    """
    follow, indptr, indices, dist = edges.follow, table.indptr, table.indices, table.dist
    angles, sensor_range, noise, fresh, draw = ring.angles, ring.sensor_range, drawn.noise, drawn.fresh, drawn.draw
    if refused:
        follow[i] = 0
        return fresh
    low = np.inf
    target = -1
    target_d = 0.0
    for k in range(indptr[i], indptr[i + 1]):
        f = field[indices[k]]
        if f < low or (f == low and f < np.inf and dist[k] < target_d):
            low = f
            target = indices[k]
            target_d = dist[k]
    if diffuse and (target < 0 or low == 0.0):  # guided: the random walk where it grows, or nothing leads there
        follow[i] = 0
        return walk_one(heading[i], scan, angles, sensor_range, False, drawn.walk_noise, fresh)
    if target < 0:  # nothing it hears leads to growth: a persistent walk
        want = heading[i]
    elif low > 0.0:  # down the field: to the node fewest hops from a new one
        want = math.atan2(xy[target, 1] - xy[i, 1], xy[target, 0] - xy[i, 0])
    else:  # where it grows: outward, away from every deployed node it hears
        px = 0.0
        py = 0.0
        for k in range(indptr[i], indptr[i + 1]):
            j = indices[k]
            d = dist[k]
            w = 1.0 - d / r_c
            if d <= 1e-12 or w <= 0.0 or field[j] == np.inf:
                continue
            px += w * (xy[i, 0] - xy[j, 0]) / d
            py += w * (xy[i, 1] - xy[j, 1]) / d
        want = math.atan2(py, px) if math.hypot(px, py) > 1e-9 else heading[i]
    return _toward(i, want, heading, scan, angles, sensor_range, edges, draw, noise)


@njit(cache=True, inline="always")
def random_heading(heading, scan, ring, refused, normal, uniform, turn_sigma):  # pragma: no cover - numba
    """``random``: one walker's new heading from its two draws, scaled as :func:`~amronet.engine.motion.random_walk`."""
    return walk_one(heading, scan, ring.angles, ring.sensor_range, refused, turn_sigma * normal,
                    -np.pi + (2.0 * np.pi) * uniform)


@njit(cache=True, inline="always")
def walk_heading(i, heading, scan, ring, refused, normal, uniform, walk, xy, table, rule):  # pragma: no cover
    """Walker ``i``'s new heading under the walk rule ``rule`` (``walk.rule``), from its draws ``normal``, ``uniform``.

    ``walk``: the fast step's :class:`~amronet.algorithms.self_spreading.kernel_data.Walk`; ``table``: the step's
    neighbour table (the growth rules read it). The draws are scaled as the reference scales them
    (:func:`~amronet.engine.motion.random_walk`, :meth:`~amronet.algorithms.self_spreading.walks.Walker.steer`).
    The paper's random walk alone (:func:`~amronet.algorithms.self_spreading.kernels.sense_steer_drive`) calls
    :func:`random_heading` itself: no branch on the rule per walker, none of the other rules' code to compile.
    """
    if rule == RANDOM:
        return random_heading(heading[i], scan, ring, refused, normal, uniform, walk.turn_sigma)
    fresh = -np.pi + (2.0 * np.pi) * uniform
    if rule == STRAIGHT:
        return straight_one(heading[i], scan, ring.angles, ring.sensor_range, refused, fresh, uniform)
    drawn = GrowthDraws(GROWTH_NOISE * walk.turn_sigma * normal, fresh, uniform, walk.turn_sigma * normal)
    return growth_one(i, heading, xy, walk.field, table, walk.r_c, scan, ring, refused, drawn,
                      EdgeFollowing(walk.follow, walk.side, walk.follow_steps), rule == GUIDED)


@njit(cache=True)
def growth_field_kernel(walk, deployed_lookup, state, indptr, indices, t):  # pragma: no cover - numba
    """The growth field into ``walk.field``: :meth:`~amronet.algorithms.self_spreading.walks.Walker.growth_field`.

    Nodes deployed now (``deployed_lookup[state]``) and first seen so get ``t`` in ``walk.deployed_at``; those
    deployed within ``walk.growth_s`` are new; one breadth-first search through the deployed nodes from all new ones
    gives every deployed node its fewest hops to a new one (``inf``: none, or not deployed). Hop counts are whole
    numbers, whatever order the search takes them in: the same field.
    """
    deployed, deployed_at, field, queue, hops = walk.deployed, walk.deployed_at, walk.field, walk.queue, walk.hops
    n = state.shape[0]
    tail = 0
    for i in range(n):
        d = deployed_lookup[state[i]]
        deployed[i] = d
        hops[i] = -1
        if d and not np.isfinite(deployed_at[i]):
            deployed_at[i] = t
    for i in range(n):
        if deployed[i] and t - deployed_at[i] <= walk.growth_s:
            queue[tail] = i
            hops[i] = 0
            tail += 1
    head = 0
    while head < tail:
        u = queue[head]
        head += 1
        for e in range(indptr[u], indptr[u + 1]):
            v = indices[e]
            if deployed[v] and hops[v] < 0:
                hops[v] = hops[u] + 1
                queue[tail] = v
                tail += 1
    for i in range(n):
        field[i] = float(hops[i]) if hops[i] >= 0 else np.inf
