"""How exploring routers walk in self-spreading (``algorithm.params.walk``): the paper's random walk and local rules.

The paper's routers random-walk until they are about to lose their last reference (section 4.2); its conclusion
says the walk "could be improved by adding more local rules" (section 7). Every rule here uses only what a router
senses or hears: its own range scan, its own heading and last move, and its row of the neighbour table (the nodes
it hears, their link lengths, and what they announce: state, position, and what the network's routing spreads).

* ``random`` — the paper's: keep the heading up to Gaussian noise (``turn_noise`` radians per square-root second);
  a forward beam that sees something turns the router to the escape heading
  (:func:`~amronet.engine.motion.escape_one`); a refused move gives it a fresh uniform heading.
* ``straight`` — a persistent walk: no heading noise while the way is clear, so a router crosses a room instead of
  diffusing in it; on an obstacle ahead it turns to the escape heading plus a uniform turn of up to 45 degrees
  either way (so it does not bounce along one line between two walls); a refused move: a fresh uniform heading.
* ``growth`` — go where the network grows. A deployed node is *new* for ``growth_s`` seconds after it stops (the
  base nodes are new for the first ``growth_s``); the network's routing spreads, as it spreads hop counts, each
  deployed node's hops to the nearest new one (the *growth field*, ``inf`` when there is none). A walking router
  heads for the node it hears with the lowest field value (nearest among equals); where it hears a new node (field
  0) it heads outward instead, away from every deployed node it hears (``1 - d / r_c`` weights: near ones push
  hardest), until it is about to lose its last reference and stops there — where the network grows. When nothing
  it hears leads to a new node, it keeps its heading (a persistent walk). Its way to a node may be blocked (the
  unit disk links through walls): an obstacle ahead that lies between it and where it wants to go is followed
  along its edge (a bug algorithm: the obstacle kept on a side drawn at random, corners rounded) until the way is
  clear, for at most ``follow_steps`` steps. Dead ends stop attracting routers once they are full: no new node
  appears there for ``growth_s``.
* ``guided`` — ``growth``'s way to where the network grows, the paper's random walk there. A router that hears no
  new node heads down the growth field as ``growth`` does (edge following included); one that hears a new node, or
  that hears nothing leading to growth, takes the ``random`` step (heading noise, escape from what the beams see).
  So a router is carried fast across the covered area to the frontier and then attaches to it as the paper's
  walkers do, where it first meets the rim — at the tips the network grows from, not in the gaps between the
  newest nodes, which is where ``growth``'s push outward leaves it and why ``growth`` deploys more routers.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numba import njit

from amronet.algorithms.common.swarm_data import Ring
from amronet.engine.kernel_data import Csr
from amronet.engine.motion import random_walk, walk_one
from amronet.engine.network import hop_counts
from amronet.engine.sensing import beam_angles
from amronet.engine.streams import RunStreams, normal_then_uniform
from amronet.engine.table import NeighbourTable

__all__ = ["WALKS", "Walker"]

WALKS: tuple[str, ...] = ("random", "straight", "growth", "guided")
"""The walk rules, ``random`` the paper's."""

STRAIGHT_SPREAD = math.pi / 4
"""``straight``: largest extra turn, either way, off an obstacle (radians)."""
GROWTH_NOISE = 0.25
"""``growth``: heading noise as a fraction of the random walk's."""
EDGE_LEAN = 0.3
"""``growth``: how far (radians) a router following an obstacle's edge leans toward it, so as not to drift off."""
CORNER_TURN = 0.35
"""``growth``: turn per step (radians) toward the side of an edge the router has lost (rounding a corner)."""


@njit(cache=True, inline="always")
def _seen(heading, scans, angles, sensor_range):  # pragma: no cover - numba
    """Direction away from what the beams see (weighted by closeness); whether anything is seen; whether ahead."""
    px = 0.0
    py = 0.0
    seen = False
    ahead = False
    for k in range(scans.shape[0]):
        w = (sensor_range - scans[k]) / sensor_range
        if w <= 0.0:
            continue
        seen = True
        if math.cos(angles[k]) > 0.0:
            ahead = True
        a = heading + angles[k]
        px -= min(w, 1.0) * math.cos(a)
        py -= min(w, 1.0) * math.sin(a)
    if math.hypot(px, py) < 1e-9:
        return heading + math.pi, seen, ahead
    return math.atan2(py, px), seen, ahead


@njit(cache=True)
def _straight(heading, who, scans, angles, sensor_range, refused, fresh, draw):  # pragma: no cover - numba
    for m in range(who.shape[0]):
        i = who[m]
        if refused[m]:
            heading[i] = fresh[m]
            continue
        away, _, ahead = _seen(heading[i], scans[m], angles, sensor_range)
        if ahead:
            heading[i] = away + STRAIGHT_SPREAD * (2.0 * draw[m] - 1.0)


class EdgeFollowing(NamedTuple):
    """``growth``: the routers following an obstacle's edge (the walker's arrays, changed in place)."""

    follow: np.ndarray
    """``int64 (N,)``: steps left following an obstacle's edge."""
    side: np.ndarray
    """``int64 (N,)``: the side each router keeps the obstacle it follows on."""
    steps: int
    """At most this many steps following an obstacle's edge."""


class GrowthDraws(NamedTuple):
    """``growth`` and ``guided``: a step's random numbers, walker by walker."""

    noise: np.ndarray
    """The growth walk's heading noise."""
    fresh: np.ndarray
    """Fresh uniform headings (a refused move, a random walk's fresh start)."""
    draw: np.ndarray
    """Uniforms in ``[0, 1)``: the side of an edge to follow, the turn off an obstacle."""
    walk_noise: np.ndarray
    """``guided``: the random walk's heading noise."""


@njit(cache=True, inline="always")
def _toward(i, m, want, heading, scans, ring, edges, draws):  # pragma: no cover - numba
    """Head for ``want``; when an obstacle ahead stands in the way, follow its edge until the way is clear."""
    follow, side, draw, noise = edges.follow, edges.side, draws.draw, draws.noise
    away, seen, ahead = _seen(heading[i], scans[m], ring.angles, ring.sensor_range)
    if follow[i] > 0:
        follow[i] -= 1
        if follow[i] == 0:  # given up: off the obstacle at a random angle
            return away + (math.pi / 2) * (2.0 * draw[m] - 1.0) if seen else want + noise[m]
        if not seen:  # the edge ends (a corner, a door): round it
            return heading[i] + side[i] * CORNER_TURN
        if math.cos(want - away) > 0.2:  # the way to want leads off the obstacle
            follow[i] = 0
            return want + noise[m]
        return away + side[i] * (math.pi / 2 - EDGE_LEAN)
    if ahead:
        if math.cos(want - away) < 0.0:  # want lies beyond the obstacle: follow its edge
            follow[i] = edges.steps
            side[i] = 1 if draw[m] < 0.5 else -1
            return away + side[i] * (math.pi / 2 - EDGE_LEAN)
        return math.atan2(math.sin(want) + math.sin(away), math.cos(want) + math.cos(away))
    return want + noise[m]


@njit(cache=True)
def _growth(heading, who, xy, field, csr, r_c, scans, ring, refused, draws, edges, diffuse):  # pragma: no cover
    """``growth`` and ``guided``: the walkers ``who``'s headings from the growth ``field`` of the nodes they hear."""
    indptr, indices, dist = csr.indptr, csr.indices, csr.dist
    fresh, follow = draws.fresh, edges.follow
    for m in range(who.shape[0]):
        i = who[m]
        if refused[m]:
            heading[i] = fresh[m]
            follow[i] = 0
            continue
        low = np.inf
        target = -1
        target_d = 0.0
        for k in range(indptr[i], indptr[i + 1]):
            f = field[indices[k]]
            if f < low or (f == low and f < np.inf and dist[k] < target_d):
                low = f
                target = indices[k]
                target_d = dist[k]
        if diffuse and (target < 0 or low == 0.0):  # guided: the random walk where it grows, or nothing leads there
            follow[i] = 0
            heading[i] = walk_one(heading[i], scans[m], ring.angles, ring.sensor_range, False, draws.walk_noise[m],
                                  fresh[m])
            continue
        if target < 0:  # nothing it hears leads to growth: a persistent walk
            want = heading[i]
        elif low > 0.0:  # down the field: to the node fewest hops from a new one
            want = math.atan2(xy[target, 1] - xy[i, 1], xy[target, 0] - xy[i, 0])
        else:  # where it grows: outward, away from every deployed node it hears
            px = 0.0
            py = 0.0
            for k in range(indptr[i], indptr[i + 1]):
                j = indices[k]
                d = dist[k]
                w = 1.0 - d / r_c
                if d <= 1e-12 or w <= 0.0 or field[j] == np.inf:
                    continue
                px += w * (xy[i, 0] - xy[j, 0]) / d
                py += w * (xy[i, 1] - xy[j, 1]) / d
            want = math.atan2(py, px) if math.hypot(px, py) > 1e-9 else heading[i]
        heading[i] = _toward(i, m, want, heading, scans, ring, edges, draws)


class Walker:
    """The walk of the exploring routers of one swarm, and what the rule remembers per router.

    Args:
        rule: One of :data:`WALKS`.
        n: Number of robots.
        r_c: Communication radius.
        turn_sigma: The random walk's heading noise per step, radians.
        growth_s: ``growth``: how long a deployed node counts as new, seconds.
        follow_steps: ``growth``: at most this many steps following an obstacle's edge.
    """

    def __init__(self, rule: str, n: int, r_c: float, turn_sigma: float, growth_s: float = 10.0,
                 follow_steps: int = 200) -> None:
        if rule not in WALKS:
            raise ValueError(f"unknown walk rule {rule!r}; choose one of {', '.join(WALKS)}")
        self.rule = rule
        self.reads_network = rule in ("growth", "guided")
        """Whether the rule reads which nodes are deployed (``growth``, ``guided``)."""
        self.r_c = r_c
        self.turn_sigma = turn_sigma
        self.growth_s = growth_s
        self.follow_steps = follow_steps
        self.follow = np.zeros(n, dtype=np.int64)
        """Steps left following an obstacle's edge."""
        self.side = np.ones(n, dtype=np.int64)
        """The side each router keeps the obstacle it follows on."""
        self.deployed_at = np.full(n, np.inf)
        """When each node was first seen deployed."""

    def growth_field(self, table: NeighbourTable, deployed: np.ndarray, t: float) -> np.ndarray:
        """Hops from each deployed node to the nearest new one (``inf``: none, or not deployed)."""
        newly = deployed & ~np.isfinite(self.deployed_at)
        self.deployed_at[newly] = t
        new = np.flatnonzero(deployed & (t - self.deployed_at <= self.growth_s))
        field = hop_counts(table, new, deployed)
        field[~deployed] = np.inf
        return field

    def steer(self, heading: np.ndarray, who: np.ndarray, scans: np.ndarray, sensor_range: float,
              refused: np.ndarray, rng: np.random.Generator | RunStreams, table: NeighbourTable, xy: np.ndarray,
              deployed: np.ndarray | None, t: float) -> None:
        """Update the headings of the walking routers ``who`` in place.

        Args:
            heading: Headings of all robots ``(N,)``.
            who: The walking routers ``(M,)``.
            scans: Their range readings ``(M, n_beams)``.
            sensor_range: Maximum range of the beams.
            refused: Which of them had their last move refused ``(M,)``.
            rng: The run's generator (or a batch's streams).
            table: The step's neighbour table.
            xy: Positions of all robots (as the nodes announce them).
            deployed: Which nodes are deployed (base nodes and references); needed when :attr:`reads_network`.
            t: Simulated time, seconds.
        """
        if self.rule == "random":
            random_walk(heading, who, scans, sensor_range, refused, rng, self.turn_sigma)
            return
        field = None
        if self.reads_network:
            assert deployed is not None
            field = self.growth_field(table, deployed, t)
        normal, uniform = normal_then_uniform(rng, who)
        if not len(who):
            return
        fresh = -np.pi + (2.0 * np.pi) * uniform
        who = np.asarray(who, dtype=np.int64)
        scans = np.ascontiguousarray(scans, dtype=float)
        angles = beam_angles(scans.shape[1])
        refused = np.asarray(refused, dtype=np.bool_)
        if self.rule == "straight":  # the uniform draw: a refused router's fresh heading, or the turn off an obstacle
            _straight(heading, who, scans, angles, float(sensor_range), refused, fresh, uniform)
            return
        assert field is not None
        draws = GrowthDraws(GROWTH_NOISE * self.turn_sigma * normal, fresh, uniform, self.turn_sigma * normal)
        edges = EdgeFollowing(self.follow, self.side, self.follow_steps)
        _growth(heading, who, xy, field, Csr(table.indptr, table.indices, table.dist), float(self.r_c), scans,
                Ring(angles, float(sensor_range)), refused, draws, edges, self.rule == "guided")
