"""What a robot of an environment observes: only what it senses or hears, as bounded arrays.

Per robot (one row each, the keys of the observation space):

* ``scan`` ``(beams,)``: its range readings, metres in ``[0, sensor range]``, beam 0 along its heading;
* ``links`` ``(K, 4)``: the ``K`` strongest links its radio hears, strongest first (ties: the lower node id), each
  ``[margin dB over the usable threshold, RSSI dBm, distance m (radio ranging), 1 if the node is a relay]`` -- a
  *relay* announces that it stays put and serves as a reference (a base station's node or a deployed router);
  margins are capped at :data:`MARGIN_CAP_DB`; rows beyond what it hears are zeros, ``links_mask`` says which hold a
  link;
* ``relay`` ``(3,)``: ``[1 if it hears a relay, distance to the nearest relay it hears (the radio's reach when
  none), best margin to a relay it hears (0 when none)]`` -- what the paper's rule and the link-quality rule read;
* ``odometry`` ``(4,)``: its displacement from where it started (metres) and the cosine and sine of its heading;
* ``flags``: what it knows of itself (the environment names them);
* ``stock`` ``(1,)`` (agents): the fraction of its routers it still carries (1 with an unlimited stock);
* ``patch`` ``(P, P)`` (optional): what it has seen around itself (:mod:`amronet.env.patch`).

Never the map, never another robot's position: the same locality rule as the controllers
(:mod:`amronet.algorithms.base`).
"""

from __future__ import annotations

import numpy as np
from gymnasium import spaces
from numba import njit

from amronet.engine.radio import NeighbourTable
from amronet.engine.sensing import beam_angles, range_scan
from amronet.env.config import EnvConfig
from amronet.env.patch import SeenMaps
from amronet.world.occupancy import OccupancyMap

__all__ = ["MARGIN_CAP_DB", "Observer", "heard_links", "split"]

MARGIN_CAP_DB = 100.0
"""Link margins above this (two robots nearly touching) are reported as this, dB."""


@njit(cache=True)
def _heard(who, indptr, indices, dist, margin, relay, threshold, rows, mask, nearest, best):  # pragma: no cover
    """:func:`heard_links` per robot: its row's ``k`` strongest links by insertion, its nearest and best relay.

    The insertion moves entry numbers (``top``), and the ``k`` rows are written once at the end.
    """
    k = rows.shape[1]
    top = np.empty(k, dtype=np.int64)
    kept = np.empty(k)  # (their margins)
    for m in range(who.shape[0]):
        i = who[m]
        filled = 0
        near = np.inf
        strongest = -np.inf
        weakest = -np.inf  # the k-th strongest so far, once there are k
        for e in range(indptr[i], indptr[i + 1]):
            g = margin[e]
            if relay[indices[e]]:
                near = min(near, dist[e])
                strongest = max(strongest, g)
            # the k strongest so far, strongest first; ties go to the lower node id (rows are sorted by id)
            if filled == k:
                if g <= weakest:
                    continue
                slot = k - 1
            else:
                slot = filled
                filled += 1
            while slot > 0 and kept[slot - 1] < g:
                kept[slot] = kept[slot - 1]
                top[slot] = top[slot - 1]
                slot -= 1
            kept[slot] = g
            top[slot] = e
            if filled == k:
                weakest = kept[k - 1]
        for s in range(filled):
            e = top[s]
            rows[m, s, 0] = kept[s]
            rows[m, s, 1] = threshold + kept[s]
            rows[m, s, 2] = dist[e]
            rows[m, s, 3] = 1.0 if relay[indices[e]] else 0.0
            mask[m, s] = 1
        nearest[m] = near
        best[m] = strongest


def heard_links(table: NeighbourTable, who: np.ndarray, relay: np.ndarray, k: int
                ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The rows of the robots ``who`` of the neighbour table: the ``k`` strongest links and the nearest relay.

    Returns:
        ``(links (M, k, 4), mask (M, k), nearest relay distance (M,), best relay margin (M,))``; ``inf`` and
        ``-inf`` where a robot hears no relay; the links as :mod:`this module <amronet.env.observe>` says, uncapped.
    """
    m = len(who)
    rows = np.zeros((m, k, 4))
    mask = np.zeros((m, k), dtype=np.int8)
    nearest = np.empty(m)
    best = np.empty(m)
    _heard(np.asarray(who, dtype=np.int64), table.indptr, table.indices, np.asarray(table.dist, dtype=np.float64),
           np.asarray(table.margin, dtype=np.float64), np.asarray(relay, dtype=np.bool_), float(table.threshold_dbm),
           rows, mask, nearest, best)
    return rows, mask, nearest, best


class Observer:
    """Builds the observations of one kind of robot (agents or routers) of a loop.

    Args:
        omap: The map (only for the range readings, as the sense phase casts them).
        n_beams: Beams of the robots' rings.
        sensor_range: Their range, metres.
        reach: The radio's reach (the farthest link), metres.
        threshold_dbm: The usable-link threshold, dBm.
        flags: Names of the robot's own flags (each 0 or 1).
        stock: Whether the observation holds ``stock``.
        config: The environment's configuration (links, patch).
        n: How many robots are observed (the patch memory's rows).
    """

    def __init__(self, omap: OccupancyMap, n_beams: int, sensor_range: float, reach: float, threshold_dbm: float,
                 flags: tuple[str, ...], stock: bool, config: EnvConfig, n: int) -> None:
        self.omap = omap
        self.n_beams = n_beams
        self.sensor_range = float(sensor_range)
        self.reach = float(reach)
        self.threshold_dbm = float(threshold_dbm)
        self.flags = flags
        self.stock = stock
        self.k = config.links
        self.angles = beam_angles(n_beams)
        xmin, xmax, ymin, ymax = omap.extent
        self.span = np.array([xmax - xmin, ymax - ymin])
        self.link_caps = np.array([MARGIN_CAP_DB, self.threshold_dbm + MARGIN_CAP_DB, self.reach, 1.0])
        """The largest value of each column of ``links`` (a relay flag is at most 1 already)."""
        self.seen = SeenMaps(n, omap.extent, config.patch_cell, config.patch) if config.patch else None

    def space(self) -> spaces.Dict:
        """The observation space of one robot."""
        f64 = np.float64
        k, cap = self.k, MARGIN_CAP_DB
        low_link = np.tile([0.0, self.threshold_dbm, 0.0, 0.0], (k, 1))
        high_link = np.tile([cap, self.threshold_dbm + cap, self.reach, 1.0], (k, 1))
        out = {
            "scan": spaces.Box(0.0, self.sensor_range, (self.n_beams,), f64),
            "links": spaces.Box(low_link, high_link, (k, 4), f64),
            "links_mask": spaces.MultiBinary(k),
            "relay": spaces.Box(np.zeros(3), np.array([1.0, self.reach, cap]), (3,), f64),
            "odometry": spaces.Box(np.array([-self.span[0], -self.span[1], -1.0, -1.0]),
                                   np.array([self.span[0], self.span[1], 1.0, 1.0]), (4,), f64),
            "flags": spaces.MultiBinary(len(self.flags)),
        }
        if self.stock:
            out["stock"] = spaces.Box(0.0, 1.0, (1,), f64)
        if self.seen is not None:
            p = self.seen.size
            out["patch"] = spaces.Box(0, 2, (p, p), np.int8)
        return spaces.Dict(out)

    def reset(self) -> None:
        """Forget what the robots have seen (a new episode)."""
        if self.seen is not None:
            self.seen.grid[:] = 0

    def observe(self, xy: np.ndarray, heading: np.ndarray, radius: np.ndarray, table: NeighbourTable,
                relay: np.ndarray, who: np.ndarray, start_xy: np.ndarray, flags: np.ndarray,
                stock: np.ndarray | None = None, rows: np.ndarray | None = None) -> dict[str, np.ndarray]:
        """The observations of the robots ``who`` (global indices), stacked ``(M, ...)`` per key.

        Args:
            xy: Positions of all robots (only ``who``'s are read, and others' for the range readings' bodies).
            heading: Headings of all robots.
            radius: Body radii of all robots (other bodies stop beams).
            table: The neighbour table of the positions ``xy``.
            relay: Which nodes are relays (deployed: base nodes and deployed routers), ``(N,)``.
            who: The observed robots ``(M,)``.
            start_xy: Where each of them started ``(M, 2)``.
            flags: Their flags ``(M, len(flags))``, 0 or 1.
            stock: Their stock fractions ``(M,)`` (with ``stock``).
            rows: Their rows of the patch memory ``(M,)`` (default ``0..M-1``).
        """
        scans = range_scan(self.omap, xy, heading, who, self.n_beams, self.sensor_range, radius=radius, table=table)
        links, mask, nearest, best = heard_links(table, who, relay, self.k)
        heard = np.isfinite(nearest)
        np.minimum(links, self.link_caps, out=links)
        relay_obs = np.empty((len(who), 3))
        relay_obs[:, 0] = heard
        np.minimum(nearest, self.reach, out=relay_obs[:, 1])  # (inf when none: the reach)
        relay_obs[:, 2] = np.where(heard, np.minimum(best, MARGIN_CAP_DB), 0.0)
        h = heading[who]
        odometry = np.empty((len(who), 4))
        np.clip(xy[who] - start_xy, -self.span, self.span, out=odometry[:, :2])
        odometry[:, 2] = np.cos(h)  # (into contiguous arrays first: numpy's vector loops are for those)
        odometry[:, 3] = np.sin(h)
        out = {
            "scan": np.clip(scans, 0.0, self.sensor_range, out=scans),
            "links": links,
            "links_mask": mask,
            "relay": relay_obs,
            "odometry": odometry,
            "flags": np.asarray(flags, dtype=np.int8),
        }
        if self.stock:
            assert stock is not None
            out["stock"] = np.clip(np.asarray(stock, dtype=float), 0.0, 1.0)[:, None]
        if self.seen is not None:
            grids = np.arange(len(who)) if rows is None else np.asarray(rows, dtype=np.int64)
            self.seen.update(grids, xy[who], h, scans, self.angles, self.sensor_range)
            out["patch"] = self.seen.patch(grids, xy[who])
        return out


def split(stacked: dict[str, np.ndarray], names: list[str]) -> dict[str, dict[str, np.ndarray]]:
    """Per-robot observations ``{name: {key: array}}`` from stacked ones (row ``m`` is ``names[m]``'s)."""
    return {name: {key: value[m] for key, value in stacked.items()} for m, name in enumerate(names)}
