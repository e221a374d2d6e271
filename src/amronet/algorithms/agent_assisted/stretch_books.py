"""The books a quiet stretch keeps step by step (:func:`~.stretch_kernels.quiet_stretch`).

The agents' connection (:class:`Links`, kept by :func:`observe_links`), under ``repair: retrace`` the agents'
way and last contact (:class:`~.repair_step.RepairStep`), and under ``agents.reverse_drop`` the agents' last contact
and path (:class:`ReverseDrop`).
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numba import njit

from amronet.algorithms.agent_assisted.release_kernels import dot2
from amronet.engine.network import agents_linked_kernel

__all__ = ["Links", "Retracing", "ReverseDrop", "back_up", "back_up_starts", "no_retracing", "no_reverse_drop",
           "observe_links"]


class Links(NamedTuple):
    """The agents' connection books (:attr:`amronet.algorithms.stepping.AgentBooks.arrays`), kept step by step.

    Per agent: whether it is linked (scratch), its connected steps, outages, longest outage and the outage going on.
    """

    linked: np.ndarray
    connected_steps: np.ndarray
    outages: np.ndarray
    longest: np.ndarray
    down_for: np.ndarray
    counts: np.ndarray
    """``[steps observed, steps all connected, outage going on, connected steps of the fraction]``."""
    sums: np.ndarray
    """``[sum of fractions, window minimum, minimum]``."""


class Retracing(NamedTuple):
    """What a stretch keeps of ``repair: retrace``'s agents (:class:`~.retrace.Retracer`), step by step.

    At the start of every step after its first, each agent linked at the last one's end (:class:`Links`) was in
    contact at this step's time, ``(first + steps done) * dt`` as the loop counts it (what
    :meth:`~.retrace.Retracer.steer_agents` notes); the stretch stops before a step in which an agent not on a
    given path would start to back up (out of contact for ``confirm`` seconds), or a backing agent would stop (it is
    linked). The agents' positions at the start of each step go into ``trail`` (the odometry of those not backing up,
    :meth:`~.retrace.Breadcrumbs.replay`). Backing agents and retracing routers head for their points with the
    repair's ``steering`` and take the next points of their ways (:mod:`~.retrace_kernels`).
    """

    trail: np.ndarray
    """Gets the agents' positions at the start of each step done ``(limit, A, 2)`` (no rows: no retrace)."""
    contact_at: np.ndarray
    """When each agent was last in contact ``(A,)``, kept in place."""
    on_path: np.ndarray
    """Which agents follow a given path (they never back up) ``(A,)``."""
    confirm: float
    """How long an agent is out of contact before it backs up, seconds."""
    first: int
    """The stretch's first step."""
    dt: float
    """Step length, seconds."""
    backing: np.ndarray
    """Which agents back up their own path ``(A,)`` (the repair's, the same all through the stretch)."""
    reach: float
    """A point of a way counts as reached within this distance (:attr:`~.retrace.Retracer.reach`)."""
    sensor_range: float
    """The agents' sensors' range."""
    max_step: np.ndarray
    """Each agent's step at its top speed ``(A,)``."""
    steering: tuple
    """The repair's :class:`~amronet.algorithms.common.goto.Steering` (a plain tuple), kept in place."""
    points: np.ndarray
    """The breadcrumbs' points ``(P, 2)`` (:attr:`~.breadcrumbs.Breadcrumbs.xy`)."""
    parent: np.ndarray
    """Each point's predecessor ``(P,)``."""
    paths: np.ndarray
    """The agents' paths ``(A, L)``, the first ``length`` of each row."""
    length: np.ndarray
    """Their lengths ``(A,)``, kept in place (backing agents forget the points they reach)."""
    tip: np.ndarray
    """Their newest points ``(A,)``, kept in place."""
    node: np.ndarray
    """Per robot, the point of its way it heads for ``(N,)``, kept in place (:attr:`~.retrace.Retracer.node`)."""
    skips: np.ndarray
    """Per robot, the points it skipped in a row ``(N,)``, kept in place."""


class ReverseDrop(NamedTuple):
    """What a stretch keeps of MARBLE's reverse drop (``agents.reverse_drop``), step by step.

    What :meth:`~.drop_switches.DropSwitches._back_up` does: the stretch stops before a step in which an agent that
    carries a router would start to back up (out of contact for more than ``after_s`` seconds,
    :func:`back_up_starts`); in the others, once the agents are steered, the agents in contact with a base station
    (on the step's table) get the step's time in ``contact_since`` and stop backing up, the others' positions go on
    their paths, and those backing up head for their path's newest point not reached yet (:func:`back_up`).
    """

    points: np.ndarray
    """The agents' paths (:attr:`~.drops.trail.Trails.points`, room for the stretch's points), kept in place (no
    rows: no reverse drop)."""
    count: np.ndarray
    """How many points of its row each agent keeps ``(A,)``, kept in place."""
    last: np.ndarray
    """Each agent's newest point ``(A, 2)``, kept in place."""
    spacing: float
    """Distance between the points of a path, metres."""
    contact_since: np.ndarray
    """When each agent was last in contact ``(A,)`` (the controller's), kept in place."""
    after_s: float
    """How long an agent is out of contact before it backs up, seconds."""
    reversing: np.ndarray
    """Which agents back up ``(A,)`` (the controller's), kept in place."""


def no_reverse_drop(m: int) -> ReverseDrop:
    """The :class:`ReverseDrop` of a stretch without ``agents.reverse_drop``, for ``m`` agents: it keeps nothing."""
    return ReverseDrop(np.zeros((0, 1, 2)), np.zeros(m, dtype=np.int64), np.zeros((m, 2)), 1.0, np.zeros(m), np.inf,
                       np.zeros(m, dtype=np.bool_))


_NO_STEERING = (np.zeros((0, 2)), np.zeros((0, 1), dtype=np.int64), np.zeros(0), np.zeros(0, dtype=np.int64), 1, 0.25)
"""The :class:`Retracing`'s steering without ``repair: retrace`` (its types as the repair's)."""


def no_retracing(m: int) -> Retracing:
    """The :class:`Retracing` of a stretch without ``repair: retrace``, for ``m`` agents: it keeps nothing."""
    none = np.zeros(0, dtype=np.int64)
    return Retracing(np.zeros((0, m, 2)), np.zeros(m), np.zeros(m, dtype=np.bool_), np.inf, 0, 1.0,
                     np.zeros(m, dtype=np.bool_), 0.0, 0.0, np.zeros(m), _NO_STEERING, np.zeros((0, 2)), none,
                     np.zeros((m, 1), dtype=np.int64), np.ones(m, dtype=np.int64), np.zeros(m, dtype=np.int64), none,
                     none)


@njit(cache=True)
def observe_links(indptr, indices, agents, books):  # pragma: no cover - numba
    """What :meth:`amronet.sim.run.Run.observe_agents` and its :class:`~amronet.sim.run.OutageTracker` do.

    ``books``: the agents' connection books (:class:`~amronet.algorithms.stepping.AgentBooks`, its arrays a
    :class:`Links`), updated in place. Returns whether every agent is linked.
    """
    bases, relay_mask, arrays = books
    linked, connected_steps, outages, longest, down_for, counts, sums = arrays
    agents_linked_kernel(indptr, indices, agents, bases, relay_mask, linked)
    a = linked.shape[0]
    up = 0
    for j in range(a):
        if linked[j]:
            up += 1
    counts[0] += 1
    if up == a:
        counts[1] += 1
        for j in range(a):
            connected_steps[j] += 1
        if counts[2]:
            for j in range(a):
                down_for[j] = 0
            counts[2] = 0
    else:
        for j in range(a):
            if linked[j]:
                connected_steps[j] += 1
                down_for[j] = 0
            else:
                if down_for[j] == 0:
                    outages[j] += 1
                down_for[j] += 1
                if down_for[j] > longest[j]:
                    longest[j] = down_for[j]
        counts[2] = 1
    frac = up / a
    counts[3] += 1
    sums[0] += frac
    sums[1] = min(sums[1], frac)
    sums[2] = min(sums[2], frac)
    return up == a


@njit(cache=True, inline="always")
def back_up_starts(reverse_drop, t, agents, left, contact):  # pragma: no cover - numba
    """Whether an agent that carries a router starts to back up in the step at time ``t`` (:class:`ReverseDrop`).

    ``contact``: whether each agent has a path to a base station on the step's table; ``left``: the routers each robot
    carries ``(N,)``. The stretch stops before such a step.
    """
    _, _, _, _, back_contact_since, back_after_s, back_reversing = reverse_drop
    for j in range(agents.shape[0]):
        if (not contact[j] and not back_reversing[j] and left[agents[j]] >= 1
                and t - back_contact_since[j] > back_after_s):
            return True
    return False


@njit(cache=True, inline="always")
def back_up(reverse_drop, t, agents, xy, heading, contact):  # pragma: no cover - numba
    """The reverse drop's part of the step at time ``t`` once the agents are steered, where no agent starts to back up.

    What :meth:`~.drop_switches.DropSwitches._back_up` does (and :class:`~.drops.trail.Trails` with it), number for
    number: a distance on a path is ``sqrt(dx * dx + dy * dy)`` (``np.linalg.norm(axis=1)``), the distance to the
    point an agent heads for that of ``np.linalg.norm`` of a 2-vector (:func:`~.release_kernels.dot2`).
    """
    back_points, back_count, back_last, back_spacing, back_contact_since, _, back_reversing = reverse_drop
    m = agents.shape[0]
    for j in range(m):
        if contact[j]:
            back_contact_since[j] = t
            back_reversing[j] = False
    for j in range(m):  # the paths of the agents not backing up
        i = agents[j]
        dx = xy[i, 0] - back_last[j, 0]
        dy = xy[i, 1] - back_last[j, 1]
        if back_reversing[j] or not math.sqrt(dx * dx + dy * dy) >= back_spacing:
            continue
        k = back_count[j]
        back_points[j, k, 0] = xy[i, 0]
        back_points[j, k, 1] = xy[i, 1]
        back_count[j] = k + 1
        back_last[j, 0] = xy[i, 0]
        back_last[j, 1] = xy[i, 1]
    for j in range(m):  # those backing up head for their path's newest point not reached yet
        if not back_reversing[j]:
            continue
        i = agents[j]
        k = back_count[j]
        while k:
            dx = back_points[j, k - 1, 0] - xy[i, 0]
            dy = back_points[j, k - 1, 1] - xy[i, 1]
            if not math.sqrt(dot2(dx, dy, dx, dy, False)) < 0.5 * back_spacing:
                break
            k -= 1
        back_count[j] = k
        if not k:  # back at the start of its path and still cut off: it gives up backing
            back_reversing[j] = False
            back_contact_since[j] = t
            continue
        back_last[j, 0] = back_points[j, k - 1, 0]
        back_last[j, 1] = back_points[j, k - 1, 1]
        heading[i] = math.atan2(back_points[j, k - 1, 1] - xy[i, 1], back_points[j, k - 1, 0] - xy[i, 0])
