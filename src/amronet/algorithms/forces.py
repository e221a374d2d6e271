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

import numpy as np

from amronet.radio import NeighbourTable
from amronet.sensing import beam_angles

__all__ = ["Links", "ObstacleHits", "clamp_norm", "links_of", "obstacle_hits", "sum_per_node"]


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
