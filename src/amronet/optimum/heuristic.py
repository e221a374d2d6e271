"""A quick connected cover: the upper bound the solver starts from.

Greedy (Guha and Khuller's connected dominating set rule, with coverage in place of domination): from the base
stations, repeatedly add the site that covers the most still uncovered rows per router it costs, a router for it and
one for each relay on the shortest chain of links from the network to it. Then drop routers the placement does
not need (in the order of fewest rows covered), one at a time, while it stays covering and connected.

S. Guha and S. Khuller, Approximation algorithms for connected dominating sets, Algorithmica 20 (1998) 374-387.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

__all__ = ["connected", "covers_all", "greedy_connected_cover", "prune"]


def _reached(links: sp.csr_matrix, base: np.ndarray, chosen: np.ndarray) -> np.ndarray:
    """Chosen sites with a chain of chosen sites to a base station."""
    reached = chosen & base
    frontier = reached.copy()
    while frontier.any():
        nxt = (links @ frontier.astype(np.int32) > 0) & chosen & ~reached
        reached |= nxt
        frontier = nxt
    return reached


def connected(links: sp.csr_matrix, base: np.ndarray, chosen: np.ndarray) -> bool:
    """Whether every chosen site has a chain of links through chosen sites to a base station."""
    return bool((_reached(links, base, chosen) == chosen).all())


def covers_all(rows: sp.csr_matrix, chosen: np.ndarray) -> bool:
    """Whether every row holds a chosen site."""
    return bool((rows @ chosen.astype(np.int32) > 0).all())


def _attach_costs(links: sp.csr_matrix, base: np.ndarray, chosen: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Routers needed to attach each site to the network (``inf``: never), and the BFS parent of each (-1: none)."""
    k = len(base)
    cost = np.full(k, np.inf)
    parent = np.full(k, -1, dtype=np.int64)
    net = chosen.astype(np.int32)
    frontier = ~chosen & (base | (links @ net > 0))
    cost[frontier] = 1
    if chosen.any():  # parent: a chosen neighbour (or none: linked to a base)
        for j in np.flatnonzero(frontier & ~base):
            nb = links.indices[links.indptr[j]:links.indptr[j + 1]]
            parent[j] = -2 - int(nb[chosen[nb]][0])  # -2 - i: attached to chosen site i
    level = 1
    while frontier.any():
        level += 1
        nxt_mask = np.zeros(k, dtype=bool)
        for j in np.flatnonzero(frontier):
            nb = links.indices[links.indptr[j]:links.indptr[j + 1]]
            new = nb[~chosen[nb] & np.isinf(cost[nb]) & ~nxt_mask[nb]]
            parent[new] = j
            nxt_mask[new] = True
        cost[nxt_mask] = level
        frontier = nxt_mask
    return cost, parent


def greedy_connected_cover(rows: sp.csr_matrix, links: sp.csr_matrix, base: np.ndarray) -> np.ndarray:
    """A covering, connected set of sites (boolean mask), pruned; see the module docstring.

    Args:
        rows: CSR ``(m, k)``: row ``i`` lists the sites that cover it.
        links: Symmetric CSR ``(k, k)`` of links between sites.
        base: ``(k,)``: the site links to a base station.

    Raises:
        ValueError: Some row cannot be covered by a site with a chain of links to a base station.
    """
    k = rows.shape[1]
    cov = rows.T.tocsr().astype(np.int32)
    uncovered = np.ones(rows.shape[0], dtype=np.int32)
    chosen = np.zeros(k, dtype=bool)
    while uncovered.any():
        gain = cov @ uncovered
        cost, parent = _attach_costs(links, base, chosen)
        score = np.where(np.isfinite(cost) & (gain > 0), gain / cost, -1.0)
        j = int(np.argmax(score))
        if score[j] <= 0:
            raise ValueError("some rows are covered by no site linked to a base station")
        while j >= 0 and not chosen[j]:  # the site and the relays on its chain
            chosen[j] = True
            uncovered[cov.indices[cov.indptr[j]:cov.indptr[j + 1]]] = 0
            j = int(parent[j])
    return prune(rows, links, base, chosen)


def prune(rows: sp.csr_matrix, links: sp.csr_matrix, base: np.ndarray, chosen: np.ndarray) -> np.ndarray:
    """Drop chosen sites one at a time, fewest rows covered first, while the rest covers every row and connects."""
    chosen = chosen.copy()
    cov = rows.T.tocsr()
    size = np.diff(cov.indptr)
    changed = True
    while changed:
        changed = False
        for j in sorted(np.flatnonzero(chosen).tolist(), key=lambda i: (size[i], i)):
            chosen[j] = False
            if covers_all(rows, chosen) and connected(links, base, chosen):
                changed = True
            else:
                chosen[j] = True
    return chosen
