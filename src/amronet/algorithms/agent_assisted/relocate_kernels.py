"""The links among the relays that ``repair: relocate`` watches, as a quiet stretch checks them step by step.

While routers relocate, the repair's look (:meth:`.relocate.Relocator.update`) changes nothing as long as the links
among the base nodes and routers are those it last saw (no loss noticed or heard again, the same routers cut off) and
no loss falls due. A stretch that steers relocating routers (:class:`~.repair_step.RepairStep`) keeps those links as
keys (:func:`network_links`) and stops before a step whose table has others (:func:`same_network_links`).
"""

from __future__ import annotations

import numpy as np
from numba import njit

__all__ = ["network_links", "same_network_links"]


@njit(cache=True)
def network_links(indptr: np.ndarray, indices: np.ndarray, network: np.ndarray) -> np.ndarray:
    """A table's links among the nodes ``network`` (a mask), row by row, as keys ``i * len(network) + j``.

    Args:
        indptr: The table's row pointers ``(N + 1,)``.
        indices: Its columns.
        network: Which nodes count ``(N,)``.

    Returns:
        The keys, in the table's order.
    """
    n = network.shape[0]
    count = 0
    for i in range(n):
        if network[i]:
            for p in range(indptr[i], indptr[i + 1]):
                if network[indices[p]]:
                    count += 1
    keys = np.empty(count, np.int64)
    k = 0
    for i in range(n):
        if network[i]:
            for p in range(indptr[i], indptr[i + 1]):
                j = indices[p]
                if network[j]:
                    keys[k] = i * n + j
                    k += 1
    return keys


@njit(cache=True)
def same_network_links(indptr: np.ndarray, indices: np.ndarray, network: np.ndarray, keys: np.ndarray) -> bool:
    """Whether a table's links among the nodes ``network`` are ``keys`` (:func:`network_links` of another table)."""
    now = network_links(indptr, indices, network)
    if now.shape[0] != keys.shape[0]:
        return False
    for k in range(now.shape[0]):
        if now[k] != keys[k]:
            return False
    return True
