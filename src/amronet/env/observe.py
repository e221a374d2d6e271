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
    """:func:`heard_links` per robot: its row's ``k`` strongest links by insertion, its nearest and best relay."""
    k = rows.shape[1]
    for m in range(who.shape[0]):
        i = who[m]
        filled = 0
        near = np.inf
        top = -np.inf
        for e in range(indptr[i], indptr[i + 1]):
            j = indices[e]
            g = margin[e]
            if relay[j]:
                near = min(near, dist[e])
                top = max(top, g)
            # the k strongest so far, strongest first; ties go to the lower node id (rows are sorted by id)
            if filled == k and g <= rows[m, k - 1, 0]:
                continue
            slot = filled if filled < k else k - 1
            while slot > 0 and rows[m, slot - 1, 0] < g:
                rows[m, slot] = rows[m, slot - 1]
                slot -= 1
            rows[m, slot, 0] = g
            rows[m, slot, 1] = threshold + g
            rows[m, slot, 2] = dist[e]
            rows[m, slot, 3] = 1.0 if relay[j] else 0.0
            if filled < k:
                filled += 1
        for s in range(filled):
            mask[m, s] = 1
        nearest[m] = near
        best[m] = top


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
        links[:, :, 0] = np.minimum(links[:, :, 0], MARGIN_CAP_DB)
        links[:, :, 1] = np.minimum(links[:, :, 1], self.threshold_dbm + MARGIN_CAP_DB)
        links[:, :, 2] = np.minimum(links[:, :, 2], self.reach)
        relay_obs = np.stack([heard.astype(float), np.where(heard, np.minimum(nearest, self.reach), self.reach),
                              np.where(heard, np.minimum(best, MARGIN_CAP_DB), 0.0)], axis=1)
        h = heading[who]
        move = np.clip(xy[who] - start_xy, -self.span, self.span)
        out = {
            "scan": np.clip(scans, 0.0, self.sensor_range),
            "links": links,
            "links_mask": mask,
            "relay": relay_obs,
            "odometry": np.concatenate([move, np.cos(h)[:, None], np.sin(h)[:, None]], axis=1),
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
