"""Graph questions about one step's network: components, paths to base stations, hop counts."""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import connected_components, dijkstra

__all__ = ["components", "connected_to", "hop_counts", "subgraph"]


def subgraph(adjacency: sp.csr_matrix, nodes: np.ndarray) -> sp.csr_matrix:
    """Adjacency restricted to the links whose both ends are in the boolean mask ``nodes``."""
    keep = sp.diags(nodes.astype(float))
    return (keep @ adjacency @ keep).tocsr()


def components(adjacency: sp.csr_matrix, nodes: np.ndarray | None = None) -> tuple[int, np.ndarray]:
    """Connected components of the graph (restricted to ``nodes`` when given).

    Returns:
        ``(count, labels)``; with ``nodes`` given, ``count`` counts components among those nodes only and the
        label of every other node is -1.
    """
    if nodes is None:
        return connected_components(adjacency, directed=False)
    _, labels = connected_components(subgraph(adjacency, nodes), directed=False)
    labels = np.where(nodes, labels, -1)
    present = np.unique(labels[nodes])
    remap = np.full(labels.max() + 2 if len(labels) else 1, -1)
    remap[present] = np.arange(len(present))
    return len(present), np.where(nodes, remap[labels], -1)


def connected_to(adjacency: sp.csr_matrix, sources: np.ndarray, nodes: np.ndarray | None = None) -> np.ndarray:
    """Boolean mask of nodes with a multi-hop path to any source (through ``nodes`` only, when given)."""
    n = adjacency.shape[0]
    if nodes is None:
        nodes = np.ones(n, dtype=bool)
    _, labels = connected_components(subgraph(adjacency, nodes), directed=False)
    src = np.asarray(sources, dtype=np.int64)
    src = src[nodes[src]]
    return np.isin(labels, labels[src]) & nodes


def hop_counts(adjacency: sp.csr_matrix, sources: np.ndarray) -> np.ndarray:
    """Fewest hops from any source to every node (``inf`` where unreachable)."""
    if len(sources) == 0:
        return np.full(adjacency.shape[0], np.inf)
    return dijkstra(adjacency, directed=False, indices=np.asarray(sources), unweighted=True, min_only=True)


def agents_connected(adjacency: sp.csr_matrix, agents: np.ndarray, bases: np.ndarray,
                     network: np.ndarray) -> np.ndarray:
    """Which agents have a multi-hop path to a base station through the AMRoNet.

    An agent counts as connected when it hears a router or base node that itself has a path to a base station
    through routers and base nodes (``network``); agents are endpoints, not relays.

    Args:
        adjacency: This step's neighbour table.
        agents: Indices of the agents ``(A,)``.
        bases: Indices of the base reference nodes.
        network: Boolean mask of the AMRoNet's nodes (routers and base nodes).

    Returns:
        Boolean mask ``(A,)``.
    """
    linked = connected_to(adjacency, bases, network)
    return (adjacency[agents] @ linked.astype(float)) > 0
