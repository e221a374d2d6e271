"""The kernels of agent-assisted deployment's fast step (:mod:`amronet.algorithms.agent_assisted.fast`).

The agents' rings, reference tracking and readings into the frontier explorer's grid in one pass; their moves in
another. Each calls the same compiled functions the phase-by-phase path calls, in the same order.

Their data come as named structures: the map's :class:`~amronet.engine.kernel_data.Grid`, neighbour lists as
:class:`~amronet.engine.kernel_data.Csr`, and the structures below. A caller hands each over as a *plain* tuple in the
order of its fields (``tuple(Tracking(...))``, built when its arrays are, not every step), and a kernel unpacks it by
position into the fields' names (``tests/test_agent_stretch.py`` checks the order). numba's dispatch types a plain
tuple in compiled code, a named tuple through its class and field names: 1-2 microseconds more for each one at every
call from Python (on the fast step's calls, 10.8 instead of 3.6 microseconds; the loose arrays cost 2.6).
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numba import njit

from amronet.algorithms.agent_assisted.explorers.frontier.knowledge import integrate_readings
from amronet.algorithms.common.references import track_row
from amronet.engine.motion import drive_one
from amronet.engine.sensing import cast_bodies_one, cast_grid_one

__all__ = ["Knowledge", "Ring", "Robots", "Tracking", "drive_movers", "integrate_agents", "sense_track_agents",
           "track_agents"]


class Robots(NamedTuple):
    """The robots' arrays the kernels read and write: the swarm's (replaced when routers are released)."""

    xy: np.ndarray
    """Positions ``(N, 2)``."""
    heading: np.ndarray
    """Headings ``(N,)``."""
    radius: np.ndarray
    """Body radii ``(N,)``."""
    status: np.ndarray
    """Network statuses ``(N,)`` (an agent takes its reference's)."""
    distance: np.ndarray
    """Distance driven ``(N,)``."""


class Ring(NamedTuple):
    """The agents' range ring."""

    angles: np.ndarray
    """The beams' angles from the heading ``(n_beams,)``."""
    sensor_range: float
    """The sensors' range, metres."""


class Tracking(NamedTuple):
    """The agent controller's reference tracking (:func:`~amronet.algorithms.common.references.track_row`)."""

    current: np.ndarray
    """Each robot's current reference ``(N,)`` (-1: none)."""
    is_ref: np.ndarray
    """Which robots are deployed nodes ``(N,)``."""
    wants_other: bool
    """Whether the tracking looks for a reference of another status (a triangle may start)."""
    left: np.ndarray
    """Routers each robot carries ``(N,)``."""
    r_eff: float
    """An agent whose nearest reference is this far is about to lose it."""
    nearest_d: np.ndarray
    """Per agent, the distance to its nearest reference in range ``(A,)``."""
    other_ref: np.ndarray
    """Per agent, its nearest reference of another status ``(A,)`` (-1: none)."""
    refused: np.ndarray
    """Which robots had their last move refused ``(N,)``."""


class Knowledge(NamedTuple):
    """What the agents' readings go into, the frontier explorer's knowledge grid, and what its update reads."""

    cells: tuple
    """The grid (:class:`~amronet.algorithms.agent_assisted.explorers.frontier.knowledge.Cells`, a plain tuple)."""
    nodes: np.ndarray
    """The deployed nodes' positions ``(D, 2)``: a reading ending on one marks no obstacle."""
    robot_r: float
    """How near a known robot a reading must end to mark none."""
    buf_r: np.ndarray
    """Scratch rows of the cells a beam crosses."""
    buf_c: np.ndarray
    """Scratch columns of those cells."""


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
def sense_track_agents(grid, robots, agents, ring, near, scans, tracking, table, integrate, knowledge,
                       stamp):  # pragma: no cover - numba
    """The agents' rings, their reference tracking and, when none of them must act, their rings in the shared grid.

    What the sense phase (:func:`~amronet.engine.sensing.range_scan`), the start of
    :meth:`~amronet.algorithms.agent_assisted.controller.AgentAssisted.decide` (:func:`track_agents`) and (with
    ``integrate``) the frontier explorer's
    :meth:`~amronet.algorithms.agent_assisted.explorers.frontier.knowledge.KnowledgeGrid.integrate` do for
    the agents, with the same functions on the same numbers.

    Args:
        grid: The map's grid (:class:`~amronet.engine.kernel_data.Grid`).
        robots: The robots (:class:`Robots`); the agents' statuses are updated.
        agents: The agents ``(A,)``.
        ring: Their ring (:class:`Ring`).
        near: The bodies near each robot (:class:`~amronet.engine.kernel_data.Csr`), for the rings.
        scans: Gets the agents' readings ``(A, n_beams)``.
        tracking: The tracking (:class:`Tracking`), updated in place.
        table: The radio's neighbour table (:class:`~amronet.engine.kernel_data.Csr`).
        integrate: Whether the readings go into the grid of ``knowledge`` (when no agent must act).
        knowledge: The grid and what its update reads (:class:`Knowledge`).
        stamp: The grid's stamp for the update.

    Returns:
        ``(triangle candidates, losing)`` as :func:`track_agents` counts them; the grid is left alone unless both
        are 0.
    """
    blocked, clear, ox, oy, res = grid
    xy, heading, radius, status, _ = robots
    angles, sensor_range = ring
    near_indptr, near_indices, near_dist = near
    current, is_ref, wants_other, left, r_eff, nearest_d, other_ref, _ = tracking
    indptr, indices, dist = table
    big = radius.max()
    n = agents.shape[0]
    for m in range(n):
        i = agents[m]
        cast_grid_one(blocked, clear, ox, oy, res, xy[i, 0], xy[i, 1], heading[i], angles, sensor_range, scans[m])
    if xy.shape[0] > 1:  # the bodies of the others
        for m in range(n):
            i = agents[m]
            cast_bodies_one(i, near_indptr, near_indices, near_dist, xy, heading[i], angles, sensor_range, radius,
                            big, scans[m])
    n_cand, n_losing = track_agents(agents, current, is_ref, status, indptr, indices, dist, wants_other, left, r_eff,
                                    nearest_d, other_ref)
    if n_cand or n_losing or not integrate:
        return n_cand, n_losing
    integrate_agents(robots, agents, ring, scans, knowledge, stamp)
    return 0, 0


@njit(cache=True)
def integrate_agents(robots, agents, ring, scans, knowledge, stamp):  # pragma: no cover - numba
    """The agents' readings in the frontier explorer's shared grid, as its ``KnowledgeGrid.integrate`` puts them.

    The arguments are :func:`sense_track_agents`'s.
    """
    xy, heading, _, _, _ = robots
    angles, sensor_range = ring
    cells, nodes, robot_r, buf_r, buf_c = knowledge
    n = agents.shape[0]
    pos = np.empty((n, 2))
    facing = np.empty(n)
    for m in range(n):
        i = agents[m]
        pos[m, 0] = xy[i, 0]
        pos[m, 1] = xy[i, 1]
        facing[m] = heading[i]
    integrate_readings(cells, pos, facing, scans, angles, sensor_range, nodes, robot_r, buf_r, buf_c, stamp)


@njit(cache=True)
def drive_movers(grid, robots, movers, length, bodies, near, reach, refused):  # pragma: no cover - numba
    """The move phase (:func:`amronet.algorithms.phases.move`) for ``movers``, each by ``length[m]``, one by one.

    Args:
        grid: The map's grid (:class:`~amronet.engine.kernel_data.Grid`).
        robots: The robots (:class:`Robots`); the movers' positions and distances are updated.
        movers: The robots that move ``(M,)``.
        length: Each one's move ``(M,)``.
        bodies: Whether bodies stop moves.
        near: The bodies near each robot (:class:`~amronet.engine.kernel_data.Csr`) within ``reach``.
        reach: The reach of the collision checks.
        refused: Set for every robot ``(N,)``: the movers' refusals, ``False`` for the rest (what the agent
            controller's ``after_move`` keeps).
    """
    xy, heading, radius, _, distance = robots
    refused[:] = False
    for m in range(movers.shape[0]):
        i = movers[m]
        r, travelled = drive_one(grid, i, heading[i], length[m], xy, radius, bodies, near, reach)
        refused[i] = r
        distance[i] += travelled
