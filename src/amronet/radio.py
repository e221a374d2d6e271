"""The radio medium: who can hear whom, computed once per step and shared by every robot.

A medium turns positions into a symmetric neighbour table (a CSR adjacency with link lengths). Controllers read
only their own row of it: what a real radio would hear. New propagation models register with
:func:`register_medium` and implement :class:`RadioMedium`; walls blocking links or path loss with shadowing are
a subclass that filters or adds links.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
from scipy.spatial import cKDTree

__all__ = ["MEDIA", "NeighbourTable", "RadioMedium", "UnitDisk", "make_medium", "register_medium"]


@dataclass(frozen=True)
class NeighbourTable:
    """One step's links.

    Attributes:
        pairs: Undirected links ``(M, 2)`` with ``i < j``.
        length: Link lengths ``(M,)`` in metres.
        adjacency: Symmetric CSR matrix ``(N, N)`` whose entries are link lengths.
        tree: The spatial index over the positions the table was built from (shared with the sensors).
    """

    pairs: np.ndarray
    length: np.ndarray
    adjacency: sp.csr_matrix
    tree: cKDTree

    @property
    def degree(self) -> np.ndarray:
        """Number of neighbours of every node."""
        return np.diff(self.adjacency.indptr)


class RadioMedium:
    """Base class of radio propagation models.

    Args:
        r_c: Communication radius in metres (the range within which a link may exist).
    """

    name = "abstract"

    def __init__(self, r_c: float) -> None:
        self.r_c = float(r_c)

    def links(self, xy: np.ndarray, tree: cKDTree) -> tuple[np.ndarray, np.ndarray]:
        """Return the undirected links ``(M, 2)`` (``i < j``) and their lengths among positions ``xy``."""
        raise NotImplementedError

    def update(self, xy: np.ndarray) -> NeighbourTable:
        """Build this step's neighbour table from all robot positions ``(N, 2)``."""
        tree = cKDTree(xy)
        pairs, length = self.links(xy, tree)
        n = len(xy)
        rows = np.concatenate([pairs[:, 0], pairs[:, 1]])
        cols = np.concatenate([pairs[:, 1], pairs[:, 0]])
        data = np.concatenate([length, length])
        adjacency = sp.csr_matrix((data, (rows, cols)), shape=(n, n))
        adjacency.sort_indices()
        return NeighbourTable(pairs=pairs, length=length, adjacency=adjacency, tree=tree)


class UnitDisk(RadioMedium):
    """Unit disk graph: two nodes are linked exactly when their distance is at most ``r_c``."""

    name = "unit-disk"

    def links(self, xy: np.ndarray, tree: cKDTree) -> tuple[np.ndarray, np.ndarray]:  # noqa: D102
        pairs = tree.query_pairs(self.r_c, output_type="ndarray").astype(np.int64)
        if len(pairs) == 0:
            return np.zeros((0, 2), dtype=np.int64), np.zeros(0)
        length = np.linalg.norm(xy[pairs[:, 0]] - xy[pairs[:, 1]], axis=1)
        return pairs, length


MEDIA: dict[str, Callable[..., RadioMedium]] = {}


def register_medium(name: str) -> Callable[[type[RadioMedium]], type[RadioMedium]]:
    """Class decorator that makes a radio medium available to scenarios under ``name``."""

    def deco(cls: type[RadioMedium]) -> type[RadioMedium]:
        MEDIA[name] = cls
        return cls

    return deco


register_medium("unit-disk")(UnitDisk)


def make_medium(model: str, r_c: float) -> RadioMedium:
    """Instantiate the radio medium registered as ``model``."""
    try:
        return MEDIA[model](r_c)
    except KeyError:
        raise ValueError(f"unknown radio model {model!r}; known: {', '.join(sorted(MEDIA))}") from None
