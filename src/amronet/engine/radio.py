"""The radio medium: who can hear whom, computed once per step and shared by every robot.

A medium turns positions into a symmetric neighbour table in CSR form (row ``i`` lists the nodes ``i`` can hear
and how far they are). Controllers read only their own row of it: what a real radio would hear. The sensors and
the collision check reuse the same table for nearby bodies, so the spatial index is built once per step.

New propagation models register with ``@MEDIA.register(name)`` and subclass :class:`RadioMedium`: a model with
walls blocking links or path loss with shadowing overrides :meth:`RadioMedium.keep` to drop candidate links
(every candidate is within ``r_c``, the largest range at which any link may exist).
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np
import scipy.sparse as sp

from amronet.engine.neighbours import neighbour_csr, pairs_from_csr
from amronet.registry import Registry

__all__ = ["MEDIA", "NeighbourTable", "RadioMedium", "UnitDisk", "make_medium"]


@dataclass(frozen=True, eq=False)
class NeighbourTable:
    """One step's links, as a symmetric CSR structure.

    Attributes:
        xy: The positions the table was built from ``(N, 2)``.
        r: Range within which candidate links were searched (the medium's ``r_c``).
        indptr: CSR row pointers ``(N + 1,)``.
        indices: Neighbour ids, sorted within each row.
        dist: Link lengths aligned with ``indices``.
        groups: Run id of every node when several runs share the table (:mod:`amronet.sim.batch`): nodes of
            different runs are never linked. ``None`` for a single run.
    """

    xy: np.ndarray
    r: float
    indptr: np.ndarray
    indices: np.ndarray
    dist: np.ndarray
    groups: np.ndarray | None = None

    def block(self, robots: slice) -> NeighbourTable:
        """The table of one run of a batch: the rows ``robots`` (a contiguous block that links only within itself).

        Equal, array for array, to the table the medium builds from that run's positions alone.
        """
        start, stop, _ = robots.indices(len(self.xy))
        lo, hi = self.indptr[start], self.indptr[stop]
        return NeighbourTable(xy=self.xy[start:stop], r=self.r, indptr=self.indptr[start:stop + 1] - lo,
                              indices=self.indices[lo:hi] - np.int32(start), dist=self.dist[lo:hi])

    @property
    def degree(self) -> np.ndarray:
        """Number of neighbours of every node."""
        return np.diff(self.indptr)

    @cached_property
    def adjacency(self) -> sp.csr_matrix:
        """The table as a SciPy CSR matrix whose entries are link lengths (for ``scipy.sparse.csgraph``)."""
        n = len(self.xy)
        return sp.csr_matrix((self.dist, self.indices, self.indptr), shape=(n, n))

    @cached_property
    def pairs(self) -> np.ndarray:
        """Undirected links ``(M, 2)`` with ``i < j``."""
        return pairs_from_csr(self.indptr, self.indices)



class RadioMedium:
    """Base class of radio propagation models.

    Args:
        r_c: Communication radius in metres (the largest range at which a link may exist).
    """

    name = "abstract"

    def __init__(self, r_c: float) -> None:
        self.r_c = float(r_c)

    def keep(self, xy: np.ndarray, indptr: np.ndarray, indices: np.ndarray, dist: np.ndarray) -> np.ndarray | None:
        """Mask of candidate links (CSR order) that exist; ``None`` keeps them all. Must be symmetric."""
        return None

    def update(self, xy: np.ndarray, groups: np.ndarray | None = None) -> NeighbourTable:
        """Build this step's neighbour table from all robot positions ``(N, 2)`` (of several runs: ``groups``)."""
        xy = np.array(xy, dtype=float)
        indptr, indices, dist = neighbour_csr(xy, self.r_c, groups)
        mask = self.keep(xy, indptr, indices, dist)
        if mask is not None:
            rows = np.repeat(np.arange(len(xy)), np.diff(indptr))[mask]
            indices, dist = indices[mask], dist[mask]
            indptr = np.zeros(len(xy) + 1, dtype=np.int64)
            np.cumsum(np.bincount(rows, minlength=len(xy)), out=indptr[1:])
        return NeighbourTable(xy=xy, r=self.r_c, indptr=indptr, indices=indices, dist=dist, groups=groups)


MEDIA: Registry[type[RadioMedium]] = Registry("radio model")
"""Radio models by name; a model registers itself with ``@MEDIA.register(name)``."""


@MEDIA.register("unit-disk")
class UnitDisk(RadioMedium):
    """Unit disk graph: two nodes are linked exactly when their distance is at most ``r_c``."""


def make_medium(model: str, r_c: float) -> RadioMedium:
    """Instantiate the radio medium registered as ``model``.

    Raises:
        ScenarioError: ``model`` is unknown (field ``radio.model``).
    """
    return MEDIA.lookup(model, "radio.model")(r_c)
