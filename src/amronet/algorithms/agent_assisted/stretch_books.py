"""The books a quiet stretch keeps step by step (:func:`~.stretch_kernels.quiet_stretch`).

The agents' connection (:class:`Links`, kept by :func:`observe_links`), under ``repair: retrace`` the agents'
way and last contact (:class:`~.repair_step.RepairStep`), and under ``agents.reverse_drop`` the agents' last contact
and path (:class:`ReverseDrop`).
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numba import njit

from amronet.engine.network import agents_linked_kernel

__all__ = ["Links", "Retracing", "ReverseDrop", "back_up_starts", "no_retracing", "no_reverse_drop", "observe_links"]


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
    given path would start to back up (out of contact for ``confirm`` seconds). The agents' positions at the start
    of each step go into ``trail`` (their odometry, :meth:`~.retrace.Breadcrumbs.replay`).
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


class ReverseDrop(NamedTuple):
    """What a stretch keeps of MARBLE's reverse drop (``agents.reverse_drop``), step by step.

    What :meth:`~.drop_switches.DropSwitches._back_up` does in a step in which no agent backs up: a stretch starts with
    none backing up, and at the start of each step the agents in contact with a base station (on its table) get the
    step's time in ``contact_since`` and every agent's position goes into ``trail`` (the caller puts them on the
    agents' paths, :meth:`~.drops.trail.Trails.update`); the stretch stops before a step in which an agent that
    carries a router would start to back up (out of contact for more than ``after_s`` seconds).
    """

    trail: np.ndarray
    """Gets the agents' positions at the start of each step begun ``(limit, A, 2)`` (no rows: no reverse drop)."""
    contact_since: np.ndarray
    """When each agent was last in contact ``(A,)`` (the controller's), kept in place."""
    after_s: float
    """How long an agent is out of contact before it backs up, seconds."""


def no_reverse_drop(m: int) -> ReverseDrop:
    """The :class:`ReverseDrop` of a stretch without ``agents.reverse_drop``, for ``m`` agents: it keeps nothing."""
    return ReverseDrop(np.zeros((0, m, 2)), np.zeros(m), np.inf)


def no_retracing(m: int) -> Retracing:
    """The :class:`Retracing` of a stretch without ``repair: retrace``, for ``m`` agents: it keeps nothing."""
    return Retracing(np.zeros((0, m, 2)), np.zeros(m), np.zeros(m, dtype=np.bool_), np.inf, 0, 1.0)


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
def back_up_starts(reverse_drop, done, t, agents, xy, left, contact):  # pragma: no cover - numba
    """The reverse drop's books at the start of step ``done`` of a stretch, at time ``t`` (:class:`ReverseDrop`).

    ``contact``: whether each agent has a path to a base station on the step's table; ``left``: the routers each robot
    carries ``(N,)``. Returns whether an agent that carries a router starts to back up in this step (then nothing is
    noted: the stretch stops before it); otherwise notes who is in contact, and where the agents are.
    """
    back_trail, back_contact_since, back_after_s = reverse_drop
    m = agents.shape[0]
    for j in range(m):
        if not contact[j] and left[agents[j]] >= 1 and t - back_contact_since[j] > back_after_s:
            return True
    for j in range(m):
        if contact[j]:
            back_contact_since[j] = t
        back_trail[done, j, 0] = xy[agents[j], 0]
        back_trail[done, j, 1] = xy[agents[j], 1]
    return False
