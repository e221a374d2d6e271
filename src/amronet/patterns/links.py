"""Links and connectivity of placed nodes in the unit-disk model at ``r`` (with :data:`LINK_SLACK`)."""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from amronet.engine.neighbours import neighbour_csr, pairs_from_csr
from amronet.engine.network import components

__all__ = ["LINK_SLACK", "is_connected", "pattern_links"]

LINK_SLACK: float = 1e-9
"""Relative slack of the link test, so that lattice neighbours exactly ``r`` apart stay linked."""


def pattern_links(xy: np.ndarray, r: float) -> np.ndarray:
    """Links ``(M, 2)`` (pairs ``i < j``) of the unit-disk graph at ``r * (1 + LINK_SLACK)``."""
    xy = np.asarray(xy, dtype=float).reshape(-1, 2)
    indptr, indices, _ = neighbour_csr(xy, r * (1 + LINK_SLACK))
    return pairs_from_csr(indptr, indices)


class _Graph(NamedTuple):
    indptr: np.ndarray
    indices: np.ndarray


def is_connected(xy: np.ndarray, r: float) -> bool:
    """Whether the unit-disk graph at ``r * (1 + LINK_SLACK)`` has one component (True for 0 or 1 node)."""
    xy = np.asarray(xy, dtype=float).reshape(-1, 2)
    n = len(xy)
    if n <= 1:
        return True
    indptr, indices, _ = neighbour_csr(xy, r * (1 + LINK_SLACK))
    return components(_Graph(indptr, indices))[0] == 1  # the compiled search: a placement tries thousands
