"""The books a quiet stretch keeps step by step (:func:`~.stretch_kernels.quiet_stretch`).

The agents' connection, and under ``repair: retrace`` the agents' way and last contact
(:class:`~.repair_step.RepairStep`).
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

__all__ = ["Links", "Retracing", "no_retracing"]


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


def no_retracing(m: int) -> Retracing:
    """The :class:`Retracing` of a stretch without ``repair: retrace``, for ``m`` agents: it keeps nothing."""
    return Retracing(np.zeros((0, m, 2)), np.zeros(m), np.zeros(m, dtype=np.bool_), np.inf, 0, 1.0)
