"""Graph questions about one step's network: components, paths to base stations, hop counts, agents.

Every function takes the graph as anything with CSR ``indptr`` and ``indices`` arrays — a
:class:`~amronet.engine.radio.NeighbourTable` or a SciPy CSR matrix — and walks it with compiled breadth-first
searches, so asking every step is cheap.
"""

from __future__ import annotations

from typing import Protocol

import numpy as np
from numba import njit

__all__ = [
    "CSRGraph",
    "agents_connected",
    "agents_linked_kernel",
    "component_counts",
    "components",
    "connected_to",
    "hop_counts",
]


class CSRGraph(Protocol):
    """A graph given by CSR arrays (row ``i`` lists the neighbours of node ``i``)."""

    indptr: np.ndarray
    indices: np.ndarray


@njit(cache=True)
def _spread(indptr, indices, allowed, queue, tail, label, labels, hops):  # pragma: no cover - numba
    """Breadth-first search from the ``tail`` nodes queued (labelled, hop 0); labels and hops of what they reach."""
    head = 0
    while head < tail:
        u = queue[head]
        head += 1
        for e in range(indptr[u], indptr[u + 1]):
            v = indices[e]
            if allowed[v] and labels[v] < 0:
                labels[v] = label
                hops[v] = hops[u] + 1
                queue[tail] = v
                tail += 1
    return tail


@njit(cache=True)
def _bfs_labels(indptr, indices, allowed, sources, labels, hops):  # pragma: no cover - numba
    """Label the allowed nodes by component (BFS); with ``sources``, search from all of them at once and count hops.

    With sources the search is one breadth-first search seeded with every allowed source (hop 0), so each node
    gets the fewest hops from *any* source, and label 0.
    """
    queue = np.empty(labels.shape[0], dtype=np.int64)
    if sources.shape[0] > 0:
        tail = 0
        for s in sources:
            if allowed[s] and labels[s] < 0:
                labels[s] = 0
                hops[s] = 0
                queue[tail] = s
                tail += 1
        return 1 if _spread(indptr, indices, allowed, queue, np.int64(tail), np.int64(0), labels, hops) > 0 else 0
    count = 0
    for s in range(labels.shape[0]):
        if not allowed[s] or labels[s] >= 0:
            continue
        labels[s] = count
        hops[s] = 0
        queue[0] = s
        _spread(indptr, indices, allowed, queue, np.int64(1), np.int64(count), labels, hops)
        count += 1
    return count


def _run(graph: CSRGraph, nodes: np.ndarray | None, sources: np.ndarray) -> tuple[int, np.ndarray, np.ndarray]:
    n = len(graph.indptr) - 1
    allowed = np.ones(n, dtype=np.bool_) if nodes is None else np.asarray(nodes, dtype=np.bool_)
    labels = np.full(n, -1, dtype=np.int64)
    hops = np.full(n, -1, dtype=np.int64)
    count = _bfs_labels(graph.indptr, graph.indices, allowed, np.asarray(sources, dtype=np.int64), labels, hops)
    return count, labels, hops


def components(graph: CSRGraph, nodes: np.ndarray | None = None) -> tuple[int, np.ndarray]:
    """Connected components of the graph (restricted to the boolean mask ``nodes`` when given).

    Returns:
        ``(count, labels)``: components are numbered from 0 in order of their lowest node id; nodes outside
        ``nodes`` get -1 and are not counted.
    """
    count, labels, _ = _run(graph, nodes, np.zeros(0, dtype=np.int64))
    return count, labels


def component_counts(graph: CSRGraph, nodes: np.ndarray, groups: np.ndarray, n_groups: int) -> np.ndarray:
    """Per group, the number of connected components of the graph restricted to ``nodes``.

    For the graph of several runs in one set of arrays (no edge joins two groups): one search for every run, the
    count :func:`components` gives for each run's block alone.

    Args:
        graph: The graph.
        nodes: Boolean mask of the nodes that count.
        groups: Group of every node, ``(N,)``.
        n_groups: Number of groups.

    Returns:
        Counts ``(n_groups,)``.
    """
    _, labels, hops = _run(graph, nodes, np.zeros(0, dtype=np.int64))
    roots = (labels >= 0) & (hops == 0)  # the node each component's search started from, one per component
    return np.bincount(groups[roots], minlength=n_groups)


def connected_to(graph: CSRGraph, sources: np.ndarray, nodes: np.ndarray | None = None) -> np.ndarray:
    """Boolean mask of nodes with a multi-hop path to any source (through ``nodes`` only, when given)."""
    if len(sources) == 0:
        return np.zeros(len(graph.indptr) - 1, dtype=bool)
    _, labels, _ = _run(graph, nodes, sources)
    return labels >= 0


def hop_counts(graph: CSRGraph, sources: np.ndarray, nodes: np.ndarray | None = None) -> np.ndarray:
    """Fewest hops from any source to every node (``inf`` where unreachable)."""
    if len(sources) == 0:
        return np.full(len(graph.indptr) - 1, np.inf)
    _, _, hops = _run(graph, nodes, sources)
    return np.where(hops >= 0, hops, np.inf).astype(float)


@njit(cache=True)
def agents_linked_kernel(indptr, indices, agents, bases, network, out):  # pragma: no cover - numba
    """``out[m]``: agent ``agents[m]`` hears a node of ``network`` that has a path to a base through ``network``."""
    n = indptr.shape[0] - 1
    labels = np.full(n, -1, dtype=np.int64)
    hops = np.empty(n, dtype=np.int64)
    if bases.shape[0] > 0:  # (with no sources, _bfs_labels would label every component)
        _bfs_labels(indptr, indices, network, bases, labels, hops)
    for m in range(agents.shape[0]):
        i = agents[m]
        out[m] = False
        for e in range(indptr[i], indptr[i + 1]):
            if labels[indices[e]] >= 0:
                out[m] = True
                break


def agents_connected(graph: CSRGraph, agents: np.ndarray, bases: np.ndarray, network: np.ndarray) -> np.ndarray:
    """Which agents have a multi-hop path to a base station through the AMRoNet.

    An agent counts as connected when it hears a router or base node that itself has a path to a base station
    through routers and base nodes (``network``); agents are endpoints, not relays. One compiled call: it runs
    every step.

    Args:
        graph: This step's neighbour table.
        agents: Indices of the agents ``(A,)``.
        bases: Indices of the base reference nodes.
        network: Boolean mask of the AMRoNet's nodes (routers and base nodes).

    Returns:
        Boolean mask ``(A,)``.
    """
    out = np.empty(len(agents), dtype=np.bool_)
    agents_linked_kernel(graph.indptr, graph.indices, np.asarray(agents, dtype=np.int64),
                   np.asarray(bases, dtype=np.int64), np.asarray(network, dtype=np.bool_), out)
    return out
