"""``repair: retrace`` in a quiet stretch: when it stops, the agents that back up, the routers that retrace.

A stretch under ``retrace`` (:class:`~.stretch_books.Retracing`) takes the steps in which the repair's own code
would only steer (:class:`~.retrace.Retracer`): agents backing up their path and routers retracing their way, each
toward a point (a breadcrumb), taking the next one once within ``reach`` of it. It stops before a step in which that
code would do more (:func:`retrace_stops`): an agent starts or stops backing up, a backing agent is back at the
start of its path, a retracing router at the start of its way, or a distance to a point is within a hair of
``reach`` (where the rounding of the distance could decide). In the other steps the routers take their next points
(:func:`aim_routers`, as :meth:`~.retrace.Retracer.steer` does first) and the backing agents theirs and are steered
(:func:`steer_backing`, as :meth:`~.retrace.Retracer.steer_agents`), where the step does so.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from amronet.algorithms.common.goto import Steering, goal_ends, steer_one

__all__ = ["aim_routers", "retrace_stops", "steer_backing"]

_SLACK = 1e-9
"""Relative width of the band around ``reach`` in which the stretch leaves a distance to the repair's own code."""


@njit(cache=True)
def retrace_stops(retracing, done, agents, xy, linked, routers):  # pragma: no cover - numba
    """Whether a stretch stops before its step ``done``; the agents' contact of that step noted.

    Args:
        retracing: The :class:`~.stretch_books.Retracing` (a plain tuple); its ``contact_at`` kept in place.
        done: Steps done.
        agents: The agents ``(A,)``.
        xy: The robots' positions at the step's start.
        linked: Which agents were linked at the end of the last step (their contact at this one's start).
        routers: The routers retracing their way in the stretch (empty: none).

    Returns:
        ``True`` where an agent starts or stops backing up, a backing agent would be at the start of its path or
        arrive or give up, a router would be at the start of its way, or a distance to a point is about ``reach``.
    """
    contact_at, on_path, confirm, first, step_dt, backs, reach = retracing[1:8]
    max_step, steering, points, parent, paths, length, _, node = retracing[9:17]
    t = (first + done) * step_dt
    for j in range(agents.shape[0] if done else 0):
        if linked[j]:
            if backs[j]:
                return True
            contact_at[j] = t
        elif not backs[j] and not on_path[j] and t - contact_at[j] >= confirm - 1e-9:
            return True
    s = Steering(*steering)
    for j in range(agents.shape[0]):
        if not backs[j]:
            continue
        a = agents[j]
        k = length[j]
        while True:
            d = _to(xy, a, points, paths[j, k - 1])
            if _about(d, reach):
                return True
            if d > reach:
                break
            if k == 1:
                return True  # (back at its start)
            k -= 1
        p = paths[j, k - 1]
        if (s.goal[a, 0] == points[p, 0] and s.goal[a, 1] == points[p, 1]) and goal_ends(a, xy, s, max_step[j]):
            return True
    for q in range(routers.shape[0]):
        i = routers[q]
        p = node[i]
        while p >= 0:
            d = _to(xy, i, points, p)
            if _about(d, reach):
                return True
            if d > reach:
                break
            p = parent[p]
        if p < 0:
            return True  # (at the start of its way)
    return False


@njit(cache=True, inline="always")
def _to(xy, i, points, p):  # pragma: no cover - numba
    """Distance from robot ``i`` to point ``p``."""
    return math.hypot(xy[i, 0] - points[p, 0], xy[i, 1] - points[p, 1])


@njit(cache=True, inline="always")
def _about(d, reach):  # pragma: no cover - numba
    """Whether ``d`` is within a hair of ``reach`` (either side)."""
    return abs(d - reach) <= _SLACK * reach


@njit(cache=True, inline="always")
def _restart(i, s, points, p):  # pragma: no cover - numba
    """Robot ``i`` heads for point ``p`` afresh (``GoalSteering.start``; its anchors and references stay none)."""
    s.goal[i, 0] = points[p, 0]
    s.goal[i, 1] = points[p, 1]
    s.last_to_goal[i] = np.inf
    s.blocked_steps[i] = 0


@njit(cache=True)
def aim_routers(retracing, routers, xy):  # pragma: no cover - numba
    """The retracing routers take the points of their ways they have reached (:meth:`~.retrace.Retracer._aim`)."""
    reach, steering, points, parent, node, skips = (retracing[7], retracing[10], retracing[11], retracing[12],
                                                    retracing[16], retracing[17])
    s = Steering(*steering)
    for q in range(routers.shape[0]):
        i = routers[q]
        start = node[i]
        p = start
        while p >= 0 and _to(xy, i, points, p) <= reach:
            p = parent[p]
            skips[i] = 0
        node[i] = p
        if p != start:
            _restart(i, s, points, p)


@njit(cache=True)
def steer_backing(retracing, agents, xy, heading, scans, angles, lengths, dt):  # pragma: no cover - numba
    """Steer the backing agents toward their points (headings set in place); their moves into ``lengths``.

    As :meth:`~.retrace.Retracer.steer_agents` does once the explorer has steered them: the points reached are
    forgotten (:meth:`~.retrace.Breadcrumbs.back`), then one go-to-goal step at the agent's top speed, with no
    anchors, its move the command's speed times the step. Returns the longest move of the agents (the move phase's
    reach).
    """
    backs, reach, sensor_range, max_step, steering, points, _, paths, length, tip = retracing[6:16]
    s = Steering(*steering)
    farthest = 0.0
    for j in range(agents.shape[0]):
        if backs[j]:
            a = agents[j]
            k = length[j]
            while k > 1 and _to(xy, a, points, paths[j, k - 1]) <= reach:
                k -= 1
            length[j] = k
            p = paths[j, k - 1]
            tip[j] = p
            if s.goal[a, 0] != points[p, 0] or s.goal[a, 1] != points[p, 1]:
                _restart(a, s, points, p)
            step, _ = steer_one(a, xy, heading, s, scans[j], angles, sensor_range, max_step[j], np.inf)
            lengths[j] = (step / dt) * dt
        farthest = max(farthest, lengths[j])
    return farthest
