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

from amronet.radio import NeighbourTable
from amronet.sensing import beam_angles
from amronet.world.occupancy import OccupancyMap
from amronet.world.space import clearance

__all__ = ["avoidance_heading", "go_to_goal", "integrate", "path_clear", "random_walk"]


@njit(cache=True)
def _escape(heading, scans, angles, sensor_range, escape, alarmed):  # pragma: no cover - numba
    for i in range(scans.shape[0]):
        px = 0.0
        py = 0.0
        alarm = False
        for k in range(scans.shape[1]):
            w = (sensor_range - scans[i, k]) / sensor_range
            if w <= 0.0:
                continue
            if w > 1.0:
                w = 1.0
            if math.cos(angles[k]) > 1e-9:
                alarm = True
            a = heading[i] + angles[k]
            px -= w * math.cos(a)
            py -= w * math.sin(a)
        alarmed[i] = alarm
        if alarm and math.hypot(px, py) < 1e-9:
            escape[i] = heading[i] + math.pi  # head-on symmetric readings cancel out: turn around
        else:
            escape[i] = math.atan2(py, px)


def avoidance_heading(heading: np.ndarray, scans: np.ndarray, sensor_range: float) -> tuple[np.ndarray, np.ndarray]:
    """Direction that points away from what the beams see, weighted by closeness.

    Each beam reading ``d < sensor_range`` pushes with weight ``(sensor_range - d) / sensor_range`` away from
    its direction; the escape heading is the direction of the summed push.

    Args:
        heading: Headings of the sensing robots, ``(M,)``.
        scans: Their ranges, ``(M, n_beams)``.
        sensor_range: Maximum range; beams reading at least this see nothing.

    Returns:
        ``(escape_heading, alarmed)``: the heading away from the obstacles and a mask of robots for which a beam
        in the forward half (within 90 degrees of the heading) sees something.
    """
    escape = np.empty(len(heading))
    alarmed = np.empty(len(heading), dtype=np.bool_)
    if len(heading):
        _escape(np.ascontiguousarray(heading, dtype=float), np.ascontiguousarray(scans, dtype=float),
                beam_angles(scans.shape[1]), float(sensor_range), escape, alarmed)
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
    new = np.where(alarmed, escape, heading) + noise
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


@njit(cache=True)
def _move_sequentially(movers, end, ok, xy, radius, indptr, indices, refused):  # pragma: no cover - numba
    """Move robots one after another; refuse a move that brings a body closer to an overlapping neighbour."""
    for m in range(movers.shape[0]):
        i = movers[m]
        if not ok[m]:
            refused[m] = True
            continue
        nx = end[m, 0]
        ny = end[m, 1]
        bad = False
        for e in range(indptr[i], indptr[i + 1]):
            j = indices[e]
            reach = radius[i] + radius[j]
            dx = nx - xy[j, 0]
            dy = ny - xy[j, 1]
            new2 = dx * dx + dy * dy
            if new2 >= reach * reach:
                continue
            ox = xy[i, 0] - xy[j, 0]
            oy = xy[i, 1] - xy[j, 1]
            if new2 < ox * ox + oy * oy - 1e-18:
                bad = True
                break
        if bad:
            refused[m] = True
        else:
            xy[i, 0] = nx
            xy[i, 1] = ny
            refused[m] = False


def integrate(
    omap: OccupancyMap,
    xy: np.ndarray,
    movers: np.ndarray,
    displacement: np.ndarray,
    radius: np.ndarray,
    *,
    bodies: bool = True,
    table: NeighbourTable | None = None,
) -> np.ndarray:
    """Move robots by the given displacements where the whole path is free; update ``xy`` in place.

    Robots move one after another in the order of ``movers``; a move is refused when its path meets an
    obstacle, or (with ``bodies``) when it ends overlapping another robot more than before. Refused robots stay.

    Args:
        omap: The map.
        xy: Positions of all robots ``(N, 2)``; changed in place.
        movers: Indices of the robots that try to move ``(M,)``.
        displacement: Their displacements ``(M, 2)``.
        radius: Body radius of all robots ``(N,)``.
        bodies: Also refuse moves that make two bodies overlap more than before.
        table: The neighbour table of the positions before the move; when its range covers every pair that could
            touch after the move, bodies are looked up in it instead of a new spatial index.

    Returns:
        Boolean mask ``(M,)`` of refused (blocked) moves.
    """
    movers = np.asarray(movers, dtype=np.int64)
    if len(movers) == 0:
        return np.zeros(0, dtype=bool)
    start = xy[movers]
    end = start + displacement
    ok = path_clear(omap, start, end, radius[movers])
    if not bodies or len(xy) < 2:
        xy[movers[ok]] = end[ok]
        return ~ok
    longest = float(np.sqrt((displacement**2).sum(axis=1)).max())
    reach = 2.0 * float(radius.max()) + 2.0 * longest
    if table is not None and reach <= table.r:
        indptr, indices = table.indptr, table.indices
    else:
        indptr, indices = _pairs_csr(xy, reach)
    refused = np.empty(len(movers), dtype=np.bool_)
    _move_sequentially(movers, np.ascontiguousarray(end), ok, xy, radius, indptr, indices, refused)
    return refused


def _pairs_csr(xy: np.ndarray, reach: float) -> tuple[np.ndarray, np.ndarray]:
    from amronet.neighbours import neighbour_csr

    indptr, indices, _ = neighbour_csr(xy, reach)
    return indptr, indices
