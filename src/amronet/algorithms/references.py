"""Reference tracking, shared by the greedy deployment of routers (self-spreading) and of agents.

A robot keeps a *current reference*: a deployed node (base reference node or deployed router) within ``r_c``.
It keeps the same one while it stays in range and otherwise takes the nearest one it hears. From its row of
the neighbour table it also learns the nearest reference in range, and the nearest reference whose status
differs from its current reference's (the trigger of the triangular deployment).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numba import njit

from amronet.radio import NeighbourTable

__all__ = ["ReferenceView", "track_references"]


@dataclass(frozen=True)
class ReferenceView:
    """What each tracking robot knows about the references around it (arrays aligned with ``who``).

    Attributes:
        current: Current reference after this step's update, -1 if none is in range.
        nearest_distance: Distance to the nearest reference in range, ``inf`` if none.
        other: Nearest reference in range whose status differs from the current reference's, -1 if none.
        other_distance: Distance to ``other``, ``inf`` if none.
    """

    current: np.ndarray
    nearest_distance: np.ndarray
    other: np.ndarray
    other_distance: np.ndarray

    @property
    def has_reference(self) -> np.ndarray:
        """Robots that hear at least one reference."""
        return self.current >= 0


@njit(cache=True)
def _track(who, current, is_reference, status, indptr, indices, dist, new_current, nearest_d, other, other_d):
    for m in range(who.shape[0]):
        i = who[m]
        cur = current[m]
        still = False
        best = -1
        best_d = np.inf
        for e in range(indptr[i], indptr[i + 1]):
            j = indices[e]
            if not is_reference[j]:
                continue
            if j == cur:
                still = True
            if dist[e] < best_d:
                best_d = dist[e]
                best = j
        chosen = cur if still else best
        new_current[m] = chosen
        nearest_d[m] = best_d
        other[m] = -1
        other_d[m] = np.inf
        if chosen < 0 or status[chosen] < 0:
            continue
        s_cur = status[chosen]
        for e in range(indptr[i], indptr[i + 1]):
            j = indices[e]
            if is_reference[j] and status[j] >= 0 and status[j] != s_cur and dist[e] < other_d[m]:
                other_d[m] = dist[e]
                other[m] = j


def track_references(
    table: NeighbourTable,
    who: np.ndarray,
    current: np.ndarray,
    is_reference: np.ndarray,
    status: np.ndarray,
) -> ReferenceView:
    """Update the current references of the robots ``who`` from their rows of the neighbour table.

    Args:
        table: This step's neighbour table.
        who: Indices of the tracking robots ``(M,)``.
        current: Their current references before this step ``(M,)`` (-1: none).
        is_reference: Boolean mask over all nodes: which ones serve as references.
        status: Status of all nodes.

    Returns:
        The updated view; ``current`` is a new array. Ties in distance go to the lower node id.
    """
    m = len(who)
    new_current = np.empty(m, dtype=np.int64)
    nearest_d = np.empty(m)
    other = np.empty(m, dtype=np.int64)
    other_d = np.empty(m)
    _track(np.asarray(who, dtype=np.int64), np.asarray(current, dtype=np.int64), is_reference,
           status, table.indptr, table.indices, table.dist, new_current, nearest_d, other, other_d)
    return ReferenceView(new_current, nearest_d, other, other_d)
