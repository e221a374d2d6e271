"""Kinematics, collision handling and the two motion behaviours of the routers and agents.

Robots are discs that turn on the spot and drive straight (holonomic in effect, at most ``max_speed``).
Behaviours turn sensor readings into headings:

* :func:`random_walk`: keep going, with a little heading noise; when a beam sees something close, turn away
  from it (Braitenberg-style avoidance); after a blocked move, pick a new random heading.
* go-to-goal (:mod:`amronet.algorithms.common.goto`): head for the goal, and blend in the same avoidance when
  something is close.

:func:`integrate` moves robots along their headings and checks every move along its whole path: a move is
refused if the disc, swept along the path, would come closer than its radius to a blocked cell's square (exact
point-to-square distances, :func:`~amronet.world.space.path_is_clear`), so no body ever reaches into a wall or slips
through a one-pixel wall; moves that would make two bodies overlap are refused too.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from amronet.engine.bitgen import next_double, standard_normal
from amronet.engine.radio import NeighbourTable
from amronet.engine.sensing import beam_angles, body_table
from amronet.engine.streams import RunStreams, normal_then_uniform
from amronet.world.occupancy import OccupancyMap
from amronet.world.space import clearance, path_is_clear

__all__ = ["avoidance_heading", "drive", "drive_one", "escape_one", "integrate", "path_clear", "random_walk",
           "random_walk_drawing", "walk_one"]


@njit(cache=True, inline="always")
def escape_one(heading, scans, angles, sensor_range):  # pragma: no cover - numba
    """Escape heading of one robot and whether a forward beam sees something (compiled; callable from kernels).

    Each reading ``d < sensor_range`` pushes with weight ``(sensor_range - d) / sensor_range`` away from its
    beam's direction (see :func:`avoidance_heading`, the array form).

    Args:
        heading: The robot's heading in radians.
        scans: Its sonar readings ``(n_beams,)``.
        angles: The beams' angles from the heading ``(n_beams,)``.
        sensor_range: Maximum range: a reading this long sees nothing.

    Returns:
        ``(escape, alarm)``: the escape heading, and whether a beam pointing forward sees something.
    """
    px = 0.0
    py = 0.0
    alarm = False
    for k in range(scans.shape[0]):
        w = (sensor_range - scans[k]) / sensor_range
        if w <= 0.0:
            continue
        if w > 1.0:
            w = 1.0
        if math.cos(angles[k]) > 1e-9:
            alarm = True
        a = heading + angles[k]
        px -= w * math.cos(a)
        py -= w * math.sin(a)
    if alarm and math.hypot(px, py) < 1e-9:
        return heading + math.pi, alarm  # head-on symmetric readings cancel out: turn around
    return math.atan2(py, px), alarm


@njit(cache=True)
def _escape(heading, scans, angles, sensor_range, escape, alarmed):  # pragma: no cover - numba
    for i in range(scans.shape[0]):
        escape[i], alarmed[i] = escape_one(heading[i], scans[i], angles, sensor_range)


@njit(cache=True, inline="always")
def walk_one(heading, scans, angles, sensor_range, refused, noise, fresh):  # pragma: no cover - numba
    """The random walk's new heading of one robot (see :func:`random_walk`)."""
    if refused:
        return fresh
    escape, alarm = escape_one(heading, scans, angles, sensor_range)
    return (escape if alarm else heading) + noise


@njit(cache=True)
def _random_walk(heading, who, scans, angles, sensor_range, refused, noise, fresh):  # pragma: no cover - numba
    for m in range(who.shape[0]):
        i = who[m]
        heading[i] = walk_one(heading[i], scans[m], angles, sensor_range, refused[m], noise[m], fresh[m])


@njit(cache=True)
def random_walk_drawing(address, heading, who, planned, scans, angles, sensor_range, refused, turn_sigma, normal,
                        uniform):  # pragma: no cover - numba
    """:func:`random_walk` of the robots ``who[k]`` with ``planned[k]`` false, drawing from a run's generator in place.

    The same numbers as ``random_walk(heading, who[~planned], scans[~planned], sensor_range, refused[~planned], rng,
    turn_sigma)``: their standard normals, then their uniforms, from the bit generator at ``address``
    (:func:`amronet.engine.bitgen.addresses`), which advances as ``rng`` would. ``normal`` and ``uniform`` are scratch
    ``(>= len(who),)``. Returns how many robots walked (none: nothing drawn).
    """
    walking = 0
    for k in range(who.shape[0]):
        if not planned[k]:
            normal[walking] = standard_normal(address)
            walking += 1
    for k in range(walking):
        uniform[k] = next_double(address)
    w = 0
    for k in range(who.shape[0]):
        if not planned[k]:
            i = who[k]
            # (rng.normal(0.0, turn_sigma) and rng.uniform(-pi, pi), bit for bit: as random_walk scales them)
            heading[i] = walk_one(heading[i], scans[k], angles, sensor_range, refused[k], turn_sigma * normal[w],
                                  -np.pi + (2.0 * np.pi) * uniform[w])
            w += 1
    return walking


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
    who: np.ndarray,
    scans: np.ndarray,
    sensor_range: float,
    was_blocked: np.ndarray,
    rng: np.random.Generator | RunStreams,
    turn_sigma: float,
) -> None:
    """Update the headings of robots doing a random walk with obstacle avoidance, in place.

    A robot whose last move was refused picks a fresh uniform heading; one whose forward beams see something
    turns to the escape heading of :func:`avoidance_heading`; every other keeps its heading. All but the
    fresh ones then add Gaussian heading noise.

    Args:
        heading: Headings of all robots ``(N,)``; entries ``who`` are updated.
        who: The walking robots ``(M,)``.
        scans: Their range readings ``(M, n_beams)``.
        sensor_range: Maximum range of the beams.
        was_blocked: Which of them had their last move refused ``(M,)``.
        rng: The run's random generator (or the streams of a batch of runs).
        turn_sigma: Standard deviation of the heading noise per step, radians.
    """
    normal, uniform = normal_then_uniform(rng, who)
    noise = turn_sigma * normal  # rng.normal(0.0, turn_sigma, m) and rng.uniform(-pi, pi, m), bit for bit
    fresh = -np.pi + (2.0 * np.pi) * uniform
    if len(who):
        _random_walk(heading, np.asarray(who, dtype=np.int64), np.ascontiguousarray(scans, dtype=float),
                     beam_angles(scans.shape[1]), float(sensor_range), np.asarray(was_blocked, dtype=np.bool_),
                     noise, fresh)


@njit(cache=True)
def _paths_ok(blocked, clear, ox, oy, res, start, end, radius, out):  # pragma: no cover - numba
    for i in range(start.shape[0]):
        out[i] = path_is_clear(blocked, clear, ox, oy, res, start[i, 0], start[i, 1], end[i, 0], end[i, 1],
                               radius[i])


def path_clear(omap: OccupancyMap, start: np.ndarray, end: np.ndarray, radius: np.ndarray) -> np.ndarray:
    """Which straight moves keep the body clear of obstacles along their whole path.

    Args:
        omap: The map.
        start: Start points ``(M, 2)``.
        end: End points ``(M, 2)``.
        radius: Body radii ``(M,)``.

    Returns:
        Boolean mask ``(M,)``: ``True`` where the disc's whole path keeps at least its radius from every blocked
        cell's square (:func:`~amronet.world.space.path_is_clear`).
    """
    out = np.empty(len(start), dtype=np.bool_)
    if len(start):
        _paths_ok(
            omap.blocked.view(np.uint8), clearance(omap), float(omap.origin[0]), float(omap.origin[1]),
            float(omap.resolution), np.ascontiguousarray(start, dtype=float), np.ascontiguousarray(end, dtype=float),
            np.ascontiguousarray(radius, dtype=float), out,
        )
    return out


@njit(cache=True, inline="always")
def plan_one(blocked, clear, ox, oy, res, x0, y0, heading, length, radius_i):  # pragma: no cover - numba
    """Where a robot at ``(x0, y0)`` would end after ``length`` along ``heading``, and whether the map lets it.

    ``(path clear, x, y)``: the obstacle half of :func:`drive_one`; it depends on the robot alone.
    """
    nx = x0 + length * math.cos(heading)
    ny = y0 + length * math.sin(heading)
    c0 = int(math.floor((x0 - ox) / res))
    r0 = int(math.floor((y0 - oy) / res))
    rows, cols = clear.shape
    roomy = 0 <= r0 < rows and 0 <= c0 < cols and clear[r0, c0] >= radius_i + length + 1.5 * res
    return roomy or path_is_clear(blocked, clear, ox, oy, res, x0, y0, nx, ny, radius_i), nx, ny


@njit(cache=True, inline="always")
def commit_one(i, x0, y0, nx, ny, xy, radius, bodies, indptr, indices, dist, near):  # pragma: no cover - numba
    """Move robot ``i`` from ``(x0, y0)`` to its planned ``(nx, ny)`` unless a body forbids it.

    The body half of :func:`drive_one` (against its neighbours as they stand now): ``(refused, travelled)``.
    """
    if bodies:
        for e in range(indptr[i], indptr[i + 1]):
            if dist[e] > near:
                continue  # too far apart before this step to touch after it
            j = indices[e]
            reach = radius[i] + radius[j]
            ex = nx - xy[j, 0]
            ey = ny - xy[j, 1]
            new2 = ex * ex + ey * ey
            if new2 >= reach * reach:
                continue
            ox_ = x0 - xy[j, 0]
            oy_ = y0 - xy[j, 1]
            if new2 < ox_ * ox_ + oy_ * oy_ - 1e-18:
                return True, 0.0
    xy[i, 0] = nx
    xy[i, 1] = ny
    return False, math.hypot(nx - x0, ny - y0)


@njit(cache=True, inline="always")
def drive_one(grid, i, heading, length, xy, radius, bodies, csr, near):  # pragma: no cover - numba
    """Move robot ``i`` by ``length`` along ``heading`` if it may (see :func:`drive`); ``(refused, travelled)``.

    A move is refused when its path meets an obstacle of the map's :class:`~amronet.engine.kernel_data.Grid`
    (:func:`plan_one`), or (with ``bodies``) when it brings the body closer to a neighbour it overlaps at the end
    (:func:`commit_one`; neighbours from the :class:`~amronet.engine.kernel_data.Csr` ``csr``, those farther than
    ``near`` skipped).
    """
    blocked, clear, ox, oy, res = grid  # by position: a plain tuple in the fields' order serves as well
    indptr, indices, dist = csr
    x0 = xy[i, 0]
    y0 = xy[i, 1]
    free, nx, ny = plan_one(blocked, clear, ox, oy, res, x0, y0, heading, length, radius[i])
    if not free:
        return True, 0.0
    return commit_one(i, x0, y0, nx, ny, xy, radius, bodies, indptr, indices, dist, near)


@njit(cache=True)
def _drive(grid, movers, heading, length, xy, radius, bodies, csr, near, refused, travelled):  # pragma: no cover
    """Move robots one after another (:func:`drive_one`)."""
    for m in range(movers.shape[0]):
        refused[m], travelled[m] = drive_one(grid, movers[m], heading[m], length[m], xy, radius, bodies, csr, near)


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
    displacement = np.asarray(displacement, dtype=float).reshape(-1, 2)
    heading = np.arctan2(displacement[:, 1], displacement[:, 0])
    length = np.hypot(displacement[:, 0], displacement[:, 1])
    refused, _ = drive(omap, xy, movers, heading, length, radius, bodies=bodies, table=table)
    return refused


def drive(
    omap: OccupancyMap,
    xy: np.ndarray,
    movers: np.ndarray,
    heading: np.ndarray,
    length: np.ndarray,
    radius: np.ndarray,
    *,
    bodies: bool = True,
    table: NeighbourTable | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """Drive robots straight along their headings; the fused form of :func:`integrate` used by the step.

    Args:
        omap: The map.
        xy: Positions of all robots ``(N, 2)``; changed in place.
        movers: Indices of the robots that try to move ``(M,)``.
        heading: Their headings ``(M,)``.
        length: How far each tries to go ``(M,)`` (speed times step length).
        radius: Body radius of all robots ``(N,)``.
        bodies: Also refuse moves that make two bodies overlap more than before.
        table: Neighbour table of the positions before the move (see :func:`integrate`).

    Returns:
        ``(refused, travelled)``: refused moves ``(M,)`` and the distance each mover travelled (0 if refused).
    """
    movers = np.asarray(movers, dtype=np.int64)
    m = len(movers)
    refused = np.ones(m, dtype=np.bool_)
    travelled = np.zeros(m)
    if m == 0:
        return refused, travelled
    heading = np.ascontiguousarray(heading, dtype=float)
    length = np.ascontiguousarray(length, dtype=float)
    reach = 2.0 * float(radius.max()) + 2.0 * float(length.max())
    if bodies and len(xy) > 1:
        indptr, indices, dist = body_table(xy, reach, table)
    else:
        indptr, indices, dist = np.zeros(len(xy) + 1, dtype=np.int64), np.zeros(0, dtype=np.int32), np.zeros(0)
    # the Grid and the Csr as plain tuples in their fields' order: numba dispatches them faster than named ones
    grid = (omap.blocked.view(np.uint8), clearance(omap), float(omap.origin[0]), float(omap.origin[1]),
            float(omap.resolution))
    _drive(grid, movers, heading, length, xy, radius, bodies, (indptr, indices, dist), reach, refused, travelled)
    return refused, travelled
