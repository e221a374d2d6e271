"""Kinematics, collision handling and the two motion behaviours of the routers and agents.

Robots are discs that turn on the spot and drive straight (holonomic in effect, at most ``max_speed``).
Behaviours turn sensor readings into headings:

* :func:`random_walk`: keep going, with a little heading noise; when a beam sees something close, turn away
  from it (Braitenberg-style avoidance); after a blocked move, pick a new random heading.
* :func:`go_to_goal`: head for the goal, and blend in the same avoidance when something is close.

:func:`integrate` moves robots along their headings and checks every move along its whole path: a move is
refused if any cell the path touches is closer to an obstacle than the robot's radius, so no robot ever ends
inside an obstacle or slips through a one-pixel wall; moves that would make two bodies overlap are refused too.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit
from scipy.spatial import cKDTree

from amronet.sensing import beam_angles
from amronet.world.occupancy import OccupancyMap
from amronet.world.space import clearance

__all__ = ["avoidance_heading", "go_to_goal", "integrate", "path_clear", "random_walk"]


def avoidance_heading(heading: np.ndarray, scans: np.ndarray, sensor_range: float) -> tuple[np.ndarray, np.ndarray]:
    """Direction that points away from what the beams see, weighted by closeness.

    Args:
        heading: Headings of the sensing robots, ``(M,)``.
        scans: Their ranges, ``(M, n_beams)``.
        sensor_range: Maximum range; beams reading at least this see nothing.

    Returns:
        ``(escape_heading, alarmed)``: the heading away from the obstacles and a mask of robots for which a beam
        in the forward half (within 90 degrees of the heading) sees something.
    """
    n_beams = scans.shape[1]
    angles = beam_angles(n_beams)
    weight = np.clip((sensor_range - scans) / sensor_range, 0.0, 1.0)
    forward = np.cos(angles) > 1e-9
    alarmed = (weight[:, forward] > 0).any(axis=1)
    world = heading[:, None] + angles[None, :]
    push_x = -(weight * np.cos(world)).sum(axis=1)
    push_y = -(weight * np.sin(world)).sum(axis=1)
    escape = np.arctan2(push_y, push_x)
    # Head-on symmetric readings cancel out: then turn around.
    cancelled = (np.hypot(push_x, push_y) < 1e-9) & alarmed
    escape = np.where(cancelled, heading + np.pi, escape)
    return escape, alarmed


def random_walk(
    heading: np.ndarray,
    scans: np.ndarray,
    sensor_range: float,
    was_blocked: np.ndarray,
    rng: np.random.Generator,
    turn_sigma: float,
) -> np.ndarray:
    """New headings for robots doing a random walk with obstacle avoidance.

    Args:
        heading: Current headings ``(M,)``.
        scans: Range readings ``(M, n_beams)``.
        sensor_range: Maximum range of the beams.
        was_blocked: Robots whose last move was refused ``(M,)``; they pick a fresh uniform heading.
        rng: The run's random generator.
        turn_sigma: Standard deviation of the heading noise per step, radians.

    Returns:
        New headings ``(M,)``.
    """
    noise = rng.normal(0.0, turn_sigma, size=len(heading))
    fresh = rng.uniform(-np.pi, np.pi, size=len(heading))
    escape, alarmed = avoidance_heading(heading, scans, sensor_range)
    new = np.where(alarmed, escape + noise, heading + noise)
    return np.where(was_blocked, fresh, new)


def go_to_goal(
    xy: np.ndarray,
    heading: np.ndarray,
    goal: np.ndarray,
    scans: np.ndarray,
    sensor_range: float,
) -> np.ndarray:
    """New headings for robots driving to goals with obstacle avoidance.

    With nothing close ahead the robot heads straight for the goal; otherwise it takes the bisector of the
    goal direction and the escape direction, which slides it along walls and around other robots.

    Args:
        xy: Positions ``(M, 2)``.
        heading: Current headings ``(M,)``.
        goal: Goal points ``(M, 2)``.
        scans: Range readings ``(M, n_beams)``.
        sensor_range: Maximum range of the beams.

    Returns:
        New headings ``(M,)``.
    """
    to_goal = np.arctan2(goal[:, 1] - xy[:, 1], goal[:, 0] - xy[:, 0])
    escape, alarmed = avoidance_heading(heading, scans, sensor_range)
    blend = np.arctan2(np.sin(to_goal) + np.sin(escape), np.cos(to_goal) + np.cos(escape))
    return np.where(alarmed, blend, to_goal)


@njit(cache=True)
def _segment_ok(clear, ox, oy, res, x0, y0, x1, y1, radius):  # pragma: no cover - numba
    """Walk every cell the segment touches (Amanatides-Woo) and require clearance >= radius in each."""
    rows, cols = clear.shape
    c = int(math.floor((x0 - ox) / res))
    r = int(math.floor((y0 - oy) / res))
    c_end = int(math.floor((x1 - ox) / res))
    r_end = int(math.floor((y1 - oy) / res))
    dx = x1 - x0
    dy = y1 - y0
    step_c = 1 if dx > 0 else -1
    step_r = 1 if dy > 0 else -1
    inf = 1e300
    if dx != 0.0:
        next_x = ox + (c + (1 if dx > 0 else 0)) * res
        t_max_x = (next_x - x0) / dx
        t_delta_x = res / abs(dx)
    else:
        t_max_x = inf
        t_delta_x = inf
    if dy != 0.0:
        next_y = oy + (r + (1 if dy > 0 else 0)) * res
        t_max_y = (next_y - y0) / dy
        t_delta_y = res / abs(dy)
    else:
        t_max_y = inf
        t_delta_y = inf
    for _ in range(4 * (rows + cols) + 4):
        if r < 0 or r >= rows or c < 0 or c >= cols:
            return False
        if clear[r, c] < radius:
            return False
        if r == r_end and c == c_end:
            return True
        if t_max_x < t_max_y:
            if t_max_x > 1.0:
                return True
            c += step_c
            t_max_x += t_delta_x
        else:
            if t_max_y > 1.0:
                return True
            r += step_r
            t_max_y += t_delta_y
    return True


@njit(cache=True)
def _paths_ok(clear, ox, oy, res, start, end, radius, out):  # pragma: no cover - numba
    for i in range(start.shape[0]):
        out[i] = _segment_ok(clear, ox, oy, res, start[i, 0], start[i, 1], end[i, 0], end[i, 1], radius[i])


def path_clear(omap: OccupancyMap, start: np.ndarray, end: np.ndarray, radius: np.ndarray) -> np.ndarray:
    """Which straight moves keep the body clear of obstacles along their whole path.

    Args:
        omap: The map.
        start: Start points ``(M, 2)``.
        end: End points ``(M, 2)``.
        radius: Body radii ``(M,)``.

    Returns:
        Boolean mask ``(M,)``: ``True`` where every cell the segment touches has clearance at least the radius.
    """
    out = np.empty(len(start), dtype=np.bool_)
    if len(start):
        _paths_ok(
            clearance(omap), float(omap.origin[0]), float(omap.origin[1]), float(omap.resolution),
            np.ascontiguousarray(start, dtype=float), np.ascontiguousarray(end, dtype=float),
            np.ascontiguousarray(radius, dtype=float), out,
        )
    return out


def integrate(
    omap: OccupancyMap,
    xy: np.ndarray,
    movers: np.ndarray,
    displacement: np.ndarray,
    radius: np.ndarray,
    *,
    bodies: bool = True,
) -> np.ndarray:
    """Move robots by the given displacements where the whole path is free; update ``xy`` in place.

    Args:
        omap: The map.
        xy: Positions of all robots ``(N, 2)``; changed in place.
        movers: Indices of the robots that try to move ``(M,)``.
        displacement: Their displacements ``(M, 2)``.
        radius: Body radius of all robots ``(N,)``.
        bodies: Also refuse moves that make two bodies overlap more than before.

    Returns:
        Boolean mask ``(M,)`` of refused (blocked) moves.
    """
    movers = np.asarray(movers, dtype=np.int64)
    if len(movers) == 0:
        return np.zeros(0, dtype=bool)
    start = xy[movers]
    end = start + displacement
    ok = path_clear(omap, start, end, radius[movers])
    if bodies and len(xy) > 1:
        old = xy.copy()
        xy[movers[ok]] = end[ok]
        reach = 2.0 * float(radius.max())
        for _ in range(3):
            pairs = cKDTree(xy).query_pairs(reach, output_type="ndarray")
            if len(pairs) == 0:
                break
            i, j = pairs[:, 0], pairs[:, 1]
            new_gap = np.linalg.norm(xy[i] - xy[j], axis=1)
            old_gap = np.linalg.norm(old[i] - old[j], axis=1)
            bad = (new_gap < radius[i] + radius[j]) & (new_gap < old_gap - 1e-12)
            if not bad.any():
                break
            offenders = np.unique(np.concatenate([i[bad], j[bad]]))
            xy[offenders] = old[offenders]
        moved = np.zeros(len(xy), dtype=bool)
        moved[movers[ok]] = True
        refused = ~(np.all(xy[movers] == end, axis=1) & moved[movers])
        return refused
    xy[movers[ok]] = end[ok]
    return ~ok
