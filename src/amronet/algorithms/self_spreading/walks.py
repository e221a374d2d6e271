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

import numpy as np
from numba import njit

from amronet.algorithms.common.swarm_data import Ring
from amronet.algorithms.self_spreading.walk_kernels import (
    GROWTH_NOISE,
    EdgeFollowing,
    GrowthDraws,
    growth_one,
    straight_one,
)
from amronet.engine.kernel_data import Csr
from amronet.engine.motion import random_walk
from amronet.engine.network import hop_counts
from amronet.engine.sensing import beam_angles
from amronet.engine.streams import RunStreams, normal_then_uniform
from amronet.engine.table import NeighbourTable

__all__ = ["WALKS", "Walker"]

WALKS: tuple[str, ...] = ("random", "straight", "growth", "guided")
"""The walk rules, ``random`` the paper's (their places are the kernels' codes,
:data:`~amronet.algorithms.self_spreading.walk_kernels.RANDOM` and the others)."""


@njit(cache=True)
def _straight(heading, who, scans, angles, sensor_range, refused, fresh, draw):  # pragma: no cover - numba
    for m in range(who.shape[0]):
        i = who[m]
        heading[i] = straight_one(heading[i], scans[m], angles, sensor_range, refused[m], fresh[m], draw[m])


@njit(cache=True)
def _growth(heading, who, xy, field, csr, r_c, scans, ring, refused, draws, edges, diffuse):  # pragma: no cover
    """``growth`` and ``guided``: the walkers ``who``'s headings from the growth ``field`` of the nodes they hear."""
    for m in range(who.shape[0]):
        i = who[m]
        drawn = GrowthDraws(draws.noise[m], draws.fresh[m], draws.draw[m], draws.walk_noise[m])
        heading[i] = growth_one(i, heading, xy, field, csr, r_c, scans[m], ring, refused[m], drawn, edges, diffuse)


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
