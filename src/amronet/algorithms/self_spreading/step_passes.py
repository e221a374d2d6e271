"""The sense and move passes of self-spreading's one-thread fast step, compiled once for every walk rule.

:func:`~amronet.algorithms.self_spreading.kernels.sense_steer_drive` (the paper's random walk) and
:func:`~amronet.algorithms.self_spreading.kernels.sense_steer_drive_rules` (the other walk rules) decide their movers'
headings each in a loop of its own, between the two passes here, which do not depend on the rule: every mover's
ring (:func:`sense_movers`), then the moves (:func:`drive_movers`). Called once a step, not inlined, they are compiled
once for both kernels, where each kernel inlining them compiled its own copy (numba's inlining copies the callee's
code, and that copying took most of the kernels' compile time).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from amronet.algorithms.self_spreading.cells import drive_rooms, same_rows
from amronet.engine.robots import State
from amronet.engine.sensing import cast_rings

__all__ = ["arrive", "drive_movers", "sense_movers"]

_TRIANGLE = State.TRIANGLE
_TRIANGLE_SETTLED = State.TRIANGLE_SETTLED


@njit(cache=True)
def sense_movers(data, n_movers, s_indptr, s_indices, s_dist):  # pragma: no cover - numba
    """Every mover's ring into ``data.moves.scans``, from where everybody stands now: ``(big, close)``.

    With more than one robot the rings meet the bodies of the neighbour list ``s_indptr, s_indices, s_dist``.
    ``big``: the largest body's radius; ``close``: ``(reach, first, edges, cells)``, the movers' links no longer
    than ``reach`` as :func:`~amronet.engine.sensing.cast_rings` lists them, which the moves may meet a body on (their
    step at most the walkers'), and each mover's cell flags as its ring read them, which its move reads again.
    """
    robots, moves, ring = data.robots, data.moves, data.ring
    xy, radius, angles = robots.xy, robots.radius, ring.angles
    movers = data.tracked.movers[:n_movers]
    big = radius.max()
    dirs = (np.empty(angles.shape[0]), np.empty(angles.shape[0]))
    reach = max(ring.sensor_range + big, 2.0 * big + 2.0 * moves.roomy.length) + 1e-6
    first = np.empty(movers.shape[0] + 1, np.int64)
    edges = np.empty(s_indices.shape[0] + 1, np.int64)
    cells = np.empty(movers.shape[0], np.uint8)
    cast_rings(data.grid, ring, movers, xy, robots.heading, radius, big, xy.shape[0] > 1,
               (s_indptr, s_indices, s_dist), dirs, moves.scans, (reach, first, edges, cells))
    return big, (reach, first, edges, cells)


@njit(cache=True)
def drive_movers(data, n_movers, big, longest, s_indptr, s_indices, s_dist, d_indptr, d_indices, d_dist,
                 close):  # pragma: no cover - numba
    """The movers' moves, one after another, ``data.moves.length[m]`` along their headings; arrivals at goals.

    ``big`` and ``close``: :func:`sense_movers`'; ``longest``: the longest of the moves. With collisions (and more
    than one robot) the moves meet the bodies of ``d_indptr, d_indices, d_dist``, read from ``close`` where those
    are the rings' list (:func:`~amronet.algorithms.self_spreading.cells.drive_rooms`).
    """
    robots, moves, walk = data.robots, data.moves, data.walk
    xy, state, refused = robots.xy, robots.state, walk.refused
    movers = data.tracked.movers[:n_movers]
    sense_bodies = xy.shape[0] > 1
    drive_bodies = data.collisions and sense_bodies
    reach, first, edges, cells = close
    near = 2.0 * big + 2.0 * longest
    refused[:] = False
    listed = sense_bodies and same_rows(s_indptr, s_indices, s_dist, d_indptr, d_indices, d_dist)
    drive_rooms(data.grid, cells, moves.roomy, movers, robots.heading, moves.length, xy, robots.radius,
                drive_bodies, (d_indptr, d_indices, d_dist), (refused, robots.distance),
                (near, listed, reach, first, edges))
    arrive(movers, state, xy, data.steering.goal)


@njit(cache=True)
def arrive(movers, state, xy, goal):  # pragma: no cover - numba
    """A triangle router on its goal has arrived."""
    for m in range(movers.shape[0]):
        i = movers[m]
        if state[i] == _TRIANGLE:
            dx = xy[i, 0] - goal[i, 0]
            dy = xy[i, 1] - goal[i, 1]
            if math.sqrt(dx * dx + dy * dy) <= 1e-9:
                state[i] = _TRIANGLE_SETTLED
