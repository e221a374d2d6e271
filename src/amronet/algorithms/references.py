"""Reference tracking, shared by the greedy deployment of routers (self-spreading) and of agents.

A robot keeps a *current reference*: a deployed node (base reference node or deployed router) within ``r_c``.
It keeps the same one while it stays in range and otherwise takes the nearest one it hears. From its row of
the neighbour table it also learns the nearest reference in range, and the nearest reference whose status
differs from its current reference's (the trigger of the triangular deployment).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

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


def _first_per_row(rows: np.ndarray, values: np.ndarray, n: int) -> tuple[np.ndarray, np.ndarray]:
    """Index (into the entry arrays) of the smallest value per row, and that value; -1 / inf for empty rows."""
    best_idx = np.full(n, -1, dtype=np.int64)
    best_val = np.full(n, np.inf)
    if len(rows) == 0:
        return best_idx, best_val
    order = np.lexsort((values, rows))
    sorted_rows = rows[order]
    first = np.ones(len(order), dtype=bool)
    first[1:] = sorted_rows[1:] != sorted_rows[:-1]
    best_idx[sorted_rows[first]] = order[first]
    best_val[sorted_rows[first]] = values[order[first]]
    return best_idx, best_val


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
        The updated view; ``current`` is a new array.
    """
    m = len(who)
    sub = table.adjacency[who].tocoo()
    rows, cols, dist = sub.row.astype(np.int64), sub.col.astype(np.int64), sub.data
    keep = is_reference[cols]
    rows, cols, dist = rows[keep], cols[keep], dist[keep]
    nearest_entry, nearest_distance = _first_per_row(rows, dist, m)
    nearest = np.where(nearest_entry >= 0, cols[np.maximum(nearest_entry, 0)] if len(cols) else -1, -1)

    current = np.asarray(current, dtype=np.int64)
    still = np.zeros(m, dtype=bool)
    if len(rows):
        still[rows[cols == current[rows]]] = True
    new_current = np.where(still, current, nearest)

    other = np.full(m, -1, dtype=np.int64)
    other_distance = np.full(m, np.inf)
    if len(rows):
        cur_status = np.where(new_current >= 0, status[np.maximum(new_current, 0)], -1)
        differs = (status[cols] != cur_status[rows]) & (status[cols] >= 0) & (cur_status[rows] >= 0)
        o_entry, o_dist = _first_per_row(rows[differs], dist[differs], m)
        found = o_entry >= 0
        other[found] = cols[differs][o_entry[found]]
        other_distance[found] = o_dist[found]
    return ReferenceView(new_current, nearest_distance, other, other_distance)
