"""Triangular deployments started inside self-spreading's stretches: the controller's rules, compiled.

In a step in which an exploring router met a reference of another status whose triangle the rule does not rule out
(:func:`~amronet.algorithms.self_spreading.kernels.track_explorers` counts them), the controller's
:meth:`~amronet.algorithms.self_spreading.controller.SelfSpreading.settle_explorers` decides which deployments go
ahead (:func:`~amronet.algorithms.common.triangular.select_triangles`), sends their routers to their goals
(:func:`~amronet.algorithms.common.triangular.triangle_goal`) and stops the routers about to lose their references.
Under the rules ``none`` and ``local`` every candidate the tracking counts goes ahead unless a router of lower id
took the same pair of references in the same step; :func:`settle_with_triangles` does exactly that, with the same
operations on the same numbers, so a stretch goes on through such a step instead of ending before it. The
``global`` rule asks the deployed network's components: its steps still end the stretch. What the kernels do not
keep of a started router (its references for the link test, which a stretch never makes) is set afterwards from
``tracked.started`` (:meth:`~amronet.algorithms.self_spreading.fast.CompiledSpreading.stretch`).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from amronet.engine.robots import State

__all__ = ["settle_with_triangles"]

_REFERENCE = State.REFERENCE
_TRIANGLE = State.TRIANGLE


@njit(cache=True)
def settle_with_triangles(data, k):  # pragma: no cover - numba
    """Settle the ``k`` explorers of ``data.tracked`` as ``settle_explorers`` does under the ``none``/``local`` rule.

    Every explorer keeps its new reference; the candidates go ahead in the order of their ids, one per pair of
    references; each one started becomes a triangle router with its reference's status and its goal
    (``triangle_goal`` with ``r_eff``), and under ``local`` it and its two references are disabled (after every
    choice: the choices read the flags as they were); the others about to lose their references stop. The started
    routers are appended to ``data.tracked.started`` (its entry 0 counts them).
    """
    robots, tracking, tracked, steering = data.robots, data.tracking, data.tracked, data.steering
    state, status, xy = robots.state, robots.status, robots.xy
    current, disabled, r_c = tracking.current, tracking.disabled, tracking.r_c
    explorers, new_current, nearest, other = tracked.explorers, tracked.new_current, tracked.nearest, tracked.other
    started = tracked.started
    first = started[0]
    for m in range(k):
        i = explorers[m]
        current[i] = new_current[m]
    go = np.zeros(k, dtype=np.bool_)
    for m in range(k):  # select_triangles: the lowest id per pair of references
        c = new_current[m]
        o = other[m]
        if o < 0:
            continue
        dx = xy[c, 0] - xy[o, 0]
        dy = xy[c, 1] - xy[o, 1]
        if not math.sqrt(dx * dx + dy * dy) > r_c or (tracking.local and disabled[c] and disabled[o]):
            continue
        lo = min(c, o)
        hi = max(c, o)
        taken = False
        for p in range(m):
            if go[p] and min(new_current[p], other[p]) == lo and max(new_current[p], other[p]) == hi:
                taken = True
                break
        go[m] = not taken
    for m in range(k):
        if not go[m]:
            continue
        i = explorers[m]
        c = new_current[m]
        o = other[m]
        state[i] = _TRIANGLE
        status[i] = status[c]
        _goal(xy, i, c, o, tracking.r_eff, steering.goal)
        steering.anchors[i, 0] = c
        steering.anchors[i, 1] = o
        steering.last_to_goal[i] = np.inf
        steering.blocked_steps[i] = 0
        started[0] += 1
        started[started[0]] = i
    if tracking.local:
        for s in range(first + 1, started[0] + 1):
            i = started[s]
            disabled[i] = True
            disabled[steering.anchors[i, 0]] = True
            disabled[steering.anchors[i, 1]] = True
    for m in range(k):  # the stops
        i = explorers[m]
        c = new_current[m]
        if not go[m] and c >= 0 and nearest[m] >= tracking.r_eff:
            state[i] = _REFERENCE
            status[i] = status[c]


@njit(cache=True, inline="always")
def _goal(xy, i, c, o, r, goal):  # pragma: no cover - numba
    """``triangle_goal`` of router ``i`` between references ``c`` and ``o``, into ``goal[i]``: the same operations."""
    mx = 0.5 * (xy[c, 0] + xy[o, 0])
    my = 0.5 * (xy[c, 1] + xy[o, 1])
    ax = xy[o, 0] - xy[c, 0]
    ay = xy[o, 1] - xy[c, 1]
    a = math.sqrt(ax * ax + ay * ay)
    nx = -ay / max(a, 1e-12)
    ny = ax / max(a, 1e-12)
    if (xy[i, 0] - mx) * nx + (xy[i, 1] - my) * ny < 0:
        nx = -nx
        ny = -ny
    half = 0.5 * a
    d = math.sqrt(max(r * r - half * half, 0.0))
    goal[i, 0] = mx + d * nx
    goal[i, 1] = my + d * ny
