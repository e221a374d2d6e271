"""The kernels of agent-assisted deployment's fast step (:mod:`amronet.algorithms.agent_assisted.fast`).

The agents' rings, reference tracking and readings into the frontier explorer's grid in one pass; their moves in
another. Each calls the same compiled functions the phase-by-phase path calls, in the same order.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from amronet.algorithms.agent_assisted.explorers.frontier.knowledge import (
    FREE_FLOOR,
    HIT_GAIN,
    OCCUPIED_CAP,
    integrate_readings,
)
from amronet.algorithms.common.references import track_row
from amronet.engine.motion import drive_one
from amronet.engine.robots import State
from amronet.engine.sensing import cast_bodies_one, cast_grid_one

__all__ = ["drive_movers", "integrate_agents", "sense_track_agents", "track_agents"]

_EXPLORE = State.EXPLORE
_REFERENCE = State.REFERENCE
_TRIANGLE = State.TRIANGLE
_TRIANGLE_SETTLED = State.TRIANGLE_SETTLED



@njit(cache=True)
def track_agents(agents, current, is_reference, status, indptr, indices, dist, want_other, left, r_eff,
                 nearest_d, other):  # pragma: no cover - numba
    """Track the agents' references in place and count who must act this step.

    For every agent ``agents[m]``: its current reference ``current[agents[m]]`` is updated
    (:func:`~amronet.algorithms.common.references.track_row`), it takes that reference's status (when it has one), and
    ``nearest_d[m]`` and ``other[m]`` get the distance to the nearest reference in range and the nearest
    reference of another status. Agents are never references, so adopting a status does not change what the
    other agents see.

    Returns:
        ``(triangle candidates, losing)``: how many agents hear a reference of another status and carry a router,
        and how many are about to lose their last reference (``nearest_d >= r_eff``).
    """
    n_cand = 0
    n_losing = 0
    for m in range(agents.shape[0]):
        a = agents[m]
        cur, near, o, _ = track_row(a, current[a], is_reference, status, indptr, indices, dist, want_other)
        current[a] = cur
        nearest_d[m] = near
        other[m] = o
        if cur >= 0:
            status[a] = status[cur]
            if near >= r_eff:
                n_losing += 1
        if o >= 0 and left[a] >= 1:
            n_cand += 1
    return n_cand, n_losing


@njit(cache=True)
def sense_track_agents(blocked, clear, ox, oy, res, xy, heading, radius, agents, angles, sensor_range, s_indptr,
                       s_indices, s_dist, sense_bodies, scans, current, is_ref, status, indptr, indices, dist,
                       want_other, left, r_eff, nearest, other, integrate, score, seen, g_ox, g_oy, g_res, nodes,
                       robot_r, buf_r, buf_c, row_stamp, stamp):  # pragma: no cover - numba
    """The agents' rings, their reference tracking and, when none of them must act, their rings in the shared grid.

    What the sense phase (:func:`~amronet.engine.sensing.range_scan`), the start of
    :meth:`~amronet.algorithms.agent_assisted.controller.AgentAssisted.decide` (:func:`track_agents`) and (with
    ``integrate``)
    the frontier explorer's
    :meth:`~amronet.algorithms.agent_assisted.explorers.frontier.knowledge.KnowledgeGrid.integrate` do for
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
    """The move phase (:func:`amronet.algorithms.phases.move`) for ``movers``, each by ``length[m]``, one by one.

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
