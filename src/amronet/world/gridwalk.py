"""Walking the grid cells a segment crosses, in order (Amanatides & Woo, 1987), for compiled loops.

Two inlined steps, so that callers keep their own loop (and stop early, or record cells) without allocating::

    r, c, r_end, c_end, step_r, step_c, t_x, t_y, dt_x, dt_y = walk_start(ox, oy, res, x0, y0, x1, y1)
    while True:
        ...  # visit cell (r, c); stop when (r, c) == (r_end, c_end)
        r, c, t_x, t_y, past_end = walk_next(r, c, step_r, step_c, t_x, t_y, dt_x, dt_y)
        if past_end:
            break
"""

from __future__ import annotations

import math

from numba import njit

__all__ = ["walk_next", "walk_start"]

_INF = 1e300


@njit(cache=True, inline="always")
def _axis(origin, res, cell, p0, delta):  # pragma: no cover - numba
    """Parameter ``t`` of the first cell border crossed along one axis, and ``t`` per cell on that axis."""
    if delta == 0.0:
        return _INF, _INF
    border = origin + (cell + (1 if delta > 0 else 0)) * res
    return (border - p0) / delta, res / abs(delta)


@njit(cache=True, inline="always")
def walk_start(ox, oy, res, x0, y0, x1, y1):  # pragma: no cover - numba
    """First cell, last cell, steps and crossing parameters of the segment ``(x0, y0) -> (x1, y1)``."""
    c = int(math.floor((x0 - ox) / res))
    r = int(math.floor((y0 - oy) / res))
    c_end = int(math.floor((x1 - ox) / res))
    r_end = int(math.floor((y1 - oy) / res))
    dx = x1 - x0
    dy = y1 - y0
    t_x, dt_x = _axis(ox, res, c, x0, dx)
    t_y, dt_y = _axis(oy, res, r, y0, dy)
    return r, c, r_end, c_end, 1 if dy > 0 else -1, 1 if dx > 0 else -1, t_x, t_y, dt_x, dt_y


@njit(cache=True, inline="always")
def walk_next(r, c, step_r, step_c, t_x, t_y, dt_x, dt_y):  # pragma: no cover - numba
    """The next cell; ``past_end`` when the segment ends before reaching it."""
    if t_x < t_y:
        if t_x > 1.0:
            return r, c, t_x, t_y, True
        return r, c + step_c, t_x + dt_x, t_y, False
    if t_y > 1.0:
        return r, c, t_x, t_y, True
    return r + step_r, c, t_x, t_y + dt_y, False
