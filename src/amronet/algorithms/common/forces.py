"""Shared pieces of the virtual-force spreading algorithms (DSSA, potential fields).

A force-based router knows two things each step, and nothing else:

* the relative positions of the nodes it hears, i.e. its own row of the radio medium's neighbour table (only
  within ``r_c``: the issue's and the paper's assumption that force-based routers can localise their radio
  neighbours);
* the obstacle points its own range sensors see: beam ``b`` of robot ``i`` reading ``d < range`` puts an
  obstacle point at ``p_i + d (cos(h_i + a_b), sin(h_i + a_b))``. The beams also stop at other robots' bodies,
  as real infrared sensors would.

The functions here turn those into per-link and per-beam unit vectors, so that each algorithm is only its
force law. Everything is vectorized over the links (CSR entries) and beams of all movers at once.
"""

from __future__ import annotations

from dataclasses import dataclass

import numba
import numpy as np

from amronet.engine.radio import NeighbourTable
from amronet.engine.sensing import beam_angles

__all__ = ["Links", "ObstacleHits", "clamp_norm", "constrained_coverage_force", "constrained_coverage_forces",
           "inverse_square_obstacle_forces", "inverse_square_one", "links_of", "obstacle_hits", "sum_per_node"]


@dataclass(frozen=True)
class Links:
    """The neighbour-table entries of some robots, flattened.

    Attributes:
        row: The robot each entry belongs to, ``(E,)``.
        col: The neighbour it hears, ``(E,)``.
        dist: Their distance, ``(E,)``.
        away: Unit vector from the neighbour to the robot (pointing *away* from the neighbour), ``(E, 2)``.
    """

    row: np.ndarray
    col: np.ndarray
    dist: np.ndarray
    away: np.ndarray


def links_of(table: NeighbourTable, xy: np.ndarray, who: np.ndarray) -> Links:
    """The links of robots ``who`` as seen by them (each undirected link appears once per endpoint in ``who``).

    Two robots at exactly the same point have no direction between them; their unit vector is taken along
    the line of their indices so that they are pushed apart deterministically.
    """
    n = len(xy)
    deg = np.diff(table.indptr)
    entry_row = np.repeat(np.arange(n), deg)
    mask = np.zeros(n, dtype=bool)
    mask[who] = True
    sel = mask[entry_row]
    row, col, dist = entry_row[sel], table.indices[sel], table.dist[sel]
    vec = xy[row] - xy[col]
    safe = dist > 1e-12
    away = np.empty_like(vec)
    away[safe] = vec[safe] / dist[safe, None]
    if not safe.all():
        angle = 0.618 * np.abs(row[~safe] - col[~safe])  # a fixed direction per pair, flipped for the other end
        away[~safe] = np.stack([np.cos(angle), np.sin(angle)], axis=1) * np.sign(row[~safe] - col[~safe])[:, None]
    return Links(row=row, col=col, dist=np.maximum(dist, 1e-12), away=away)


@dataclass(frozen=True)
class ObstacleHits:
    """Obstacle points seen by the range sensors of some robots.

    Attributes:
        dist: Range of every beam that hit something, ``(H,)``.
        away: Unit vector from the hit point to the robot, ``(H, 2)``.
        row: Position of the robot in the ``who`` array passed to :func:`obstacle_hits`, ``(H,)``.
    """

    dist: np.ndarray
    away: np.ndarray
    row: np.ndarray


def obstacle_hits(scans: np.ndarray, heading: np.ndarray, sensor_range: float) -> ObstacleHits:
    """The beams of ``scans`` ``(M, B)`` that saw an obstacle, for robots with headings ``heading`` ``(M,)``."""
    m, b = scans.shape
    angles = heading[:, None] + beam_angles(b)[None, :]
    hit = scans < sensor_range - 1e-9
    rows = np.broadcast_to(np.arange(m)[:, None], (m, b))[hit]
    theta = angles[hit]
    away = -np.stack([np.cos(theta), np.sin(theta)], axis=1)
    return ObstacleHits(dist=np.maximum(scans[hit], 1e-6), away=away, row=rows)


def sum_per_node(rows: np.ndarray, vectors: np.ndarray, n: int) -> np.ndarray:
    """Sum the force vectors ``(E, 2)`` of each node ``rows`` ``(E,)`` into an ``(n, 2)`` array."""
    out = np.empty((n, 2))
    out[:, 0] = np.bincount(rows, weights=vectors[:, 0], minlength=n)
    out[:, 1] = np.bincount(rows, weights=vectors[:, 1], minlength=n)
    return out


def clamp_norm(v: np.ndarray, limit: np.ndarray | float) -> np.ndarray:
    """Scale the rows of ``v`` ``(M, 2)`` down to norm at most ``limit`` (scalar or ``(M,)``); returns a copy."""
    norm = np.hypot(v[:, 0], v[:, 1])
    scale = np.minimum(1.0, np.asarray(limit) / np.maximum(norm, 1e-300))
    return v * scale[:, None]


@numba.njit(cache=True)
def constrained_coverage_force(i, indptr, indices, dist, xy, k_cover, k_degree, q_rc, cap, k_conn):  # pragma: no cover
    """Net link force ``(fx, fy)`` on robot ``i`` (compiled; see :func:`constrained_coverage_forces`)."""
    start, stop = indptr[i], indptr[i + 1]
    critical = stop - start <= k_conn
    fx = 0.0
    fy = 0.0
    for e in range(start, stop):
        j = indices[e]
        d = dist[e]
        if d > 1e-12:
            ux = (xy[i, 0] - xy[j, 0]) / d
            uy = (xy[i, 1] - xy[j, 1]) / d
        else:  # same convention as links_of
            d = 1e-12
            a = 0.618 * abs(i - j)
            sgn = 1.0 if i > j else -1.0
            ux = np.cos(a) * sgn
            uy = np.sin(a) * sgn
        mag = min(k_cover / (d * d), cap)
        if critical:
            slack = q_rc - d
            mag -= cap if slack <= 0.0 else min(k_degree / (slack * slack), cap)
        fx += mag * ux
        fy += mag * uy
    return fx, fy


@numba.njit(cache=True)
def _constrained_coverage(who, indptr, indices, dist, xy, k_cover, k_degree, q_rc, cap, k_conn, out):  # pragma: no cov
    for m in range(len(who)):
        out[m, 0], out[m, 1] = constrained_coverage_force(who[m], indptr, indices, dist, xy, k_cover, k_degree, q_rc,
                                                          cap, k_conn)


def constrained_coverage_forces(table: NeighbourTable, xy: np.ndarray, who: np.ndarray, k_cover: float,
                                k_degree: float, q_rc: float, cap: float, k_conn: int) -> np.ndarray:
    """Net link force of Poduri & Sukhatme's constrained coverage on robots ``who`` ``(M, 2)``.

    Every link pushes with ``min(k_cover / d^2, cap)``; when the robot hears ``k_conn`` or fewer nodes its links
    are critical and also pull with ``min(k_degree / (q_rc - d)^2, cap)`` (``cap`` once stretched past
    ``q_rc``). A compiled loop over the robots' neighbour-table rows; :func:`links_of` gives the same vectors.
    """
    out = np.zeros((len(who), 2))
    _constrained_coverage(np.asarray(who, dtype=np.int64), table.indptr, table.indices, table.dist, xy,
                          float(k_cover), float(k_degree), float(q_rc), float(cap), int(k_conn), out)
    return out


@numba.njit(cache=True, inline="always")
def inverse_square_one(scans, heading, angles, max_range, k, cap):  # pragma: no cover - numba
    """Net push ``(fx, fy)`` on one robot with readings ``scans`` ``(n_beams,)`` (see the array form below)."""
    fx = 0.0
    fy = 0.0
    for b in range(scans.shape[0]):
        d = scans[b]
        if d < max_range - 1e-9:
            d = max(d, 1e-6)
            mag = min(k / (d * d), cap)
            theta = heading + angles[b]
            fx -= mag * np.cos(theta)
            fy -= mag * np.sin(theta)
    return fx, fy


@numba.njit(cache=True)
def _inverse_square_hits(scans, heading, angles, max_range, k, cap, out):  # pragma: no cover - numba
    for m in range(scans.shape[0]):
        out[m, 0], out[m, 1] = inverse_square_one(scans[m], heading[m], angles, max_range, k, cap)


def inverse_square_obstacle_forces(scans: np.ndarray, heading: np.ndarray, sensor_range: float, k: float,
                                   cap: float) -> np.ndarray:
    """Net push ``min(k / d^2, cap)`` of every beam that saw something, per robot ``(M, 2)`` (compiled).

    The same forces as summing :func:`obstacle_hits` with that law.
    """
    out = np.zeros((scans.shape[0], 2))
    _inverse_square_hits(np.ascontiguousarray(scans, dtype=float), np.asarray(heading, dtype=float),
                         beam_angles(scans.shape[1]), float(sensor_range), float(k), float(cap), out)
    return out
