"""One step's links: the neighbour table the radio medium builds and every robot reads its own row of.

Symmetric CSR arrays (who hears whom, how far) with the quality of every link (RSSI, margin over the usable
threshold, delivery ratio), the geometric view that body sensors and collision checks use, and the block of one run
of a batch. Built by :mod:`amronet.engine.radio`.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np
import scipy.sparse as sp

from amronet.engine.links import distance_margins
from amronet.engine.neighbours import pairs_from_csr
from amronet.engine.propagation import delivery_ratio

__all__ = ["NeighbourTable"]


@dataclass(eq=False)
class NeighbourTable:
    """One step's links, as a symmetric CSR structure.

    A table is a value: nothing changes its fields or arrays once it is built (the medium builds a new one every
    step). It is not a frozen dataclass only because building a frozen one costs 3 µs, a tenth of a 30-robot step.

    Attributes:
        xy: The positions the table was built from ``(N, 2)``.
        r: Every pair of nodes within ``r`` of each other is in :attr:`geometric` (the medium's search radius).
        indptr: CSR row pointers ``(N + 1,)``.
        indices: Neighbour ids, sorted within each row.
        dist: Link lengths aligned with ``indices``.
        groups: Run id of every node when several runs share the table (:mod:`amronet.sim.batch`): nodes of
            different runs are never linked. ``None`` for a single run.
        threshold_dbm: The usable-link threshold of the medium that built the table.
        link_margin: Margin of each link over the threshold in dB, aligned with ``indices`` (``None``: computed on
            first use from the distances, as the unit disk does).
        exponent: The path-loss exponent behind lazily computed margins.
        candidates: The table of every pair within ``r`` before the medium dropped links (``None``: nothing was
            dropped, this table is it).
    """

    xy: np.ndarray
    r: float
    indptr: np.ndarray
    indices: np.ndarray
    dist: np.ndarray
    groups: np.ndarray | None = None
    threshold_dbm: float = float("nan")
    link_margin: np.ndarray | None = None
    exponent: float = 2.5
    candidates: NeighbourTable | None = None

    def block(self, robots: slice) -> NeighbourTable:
        """The table of one run of a batch: the rows ``robots`` (a contiguous block that links only within itself).

        Equal, array for array, to the table the medium builds from that run's positions alone.
        """
        start, stop, _ = robots.indices(len(self.xy))
        lo, hi = self.indptr[start], self.indptr[stop]
        return NeighbourTable(xy=self.xy[start:stop], r=self.r, indptr=self.indptr[start:stop + 1] - lo,
                              indices=self.indices[lo:hi] - np.int32(start), dist=self.dist[lo:hi],
                              threshold_dbm=self.threshold_dbm, exponent=self.exponent,
                              link_margin=None if self.link_margin is None else self.link_margin[lo:hi],
                              candidates=None if self.candidates is None else self.candidates.block(robots))

    @property
    def geometric(self) -> NeighbourTable:
        """Every pair within :attr:`r`, walls or not: what the body sensors and the collision check need."""
        return self if self.candidates is None else self.candidates

    @property
    def degree(self) -> np.ndarray:
        """Number of neighbours of every node."""
        return np.diff(self.indptr)

    @cached_property
    def margin(self) -> np.ndarray:
        """Margin of every link over the usable threshold (dB), aligned with ``indices``."""
        if self.link_margin is not None:
            return self.link_margin
        # r is the range then; the link budget's law by the compiled function a stretch uses (the same last bit)
        return distance_margins(np.ascontiguousarray(self.dist, dtype=np.float64), float(self.r), 10.0 * self.exponent)

    @property
    def rssi(self) -> np.ndarray:
        """Received signal strength of every link (dBm), aligned with ``indices``: what a controller hears."""
        return self.threshold_dbm + self.margin

    @property
    def delivery(self) -> np.ndarray:
        """Packet delivery ratio of every link (:func:`~amronet.engine.propagation.delivery_ratio`)."""
        return delivery_ratio(self.margin)

    @cached_property
    def adjacency(self) -> sp.csr_matrix:
        """The table as a SciPy CSR matrix whose entries are link lengths (for ``scipy.sparse.csgraph``)."""
        n = len(self.xy)
        return sp.csr_matrix((self.dist, self.indices, self.indptr), shape=(n, n))

    @cached_property
    def pairs(self) -> np.ndarray:
        """Undirected links ``(M, 2)`` with ``i < j``."""
        return pairs_from_csr(self.indptr, self.indices)
