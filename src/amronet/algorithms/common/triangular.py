"""Triangular deployment (paper sections 4.1-4.3): joining the networks grown from different base stations.

When a robot whose current reference ``R_ij`` has status ``i`` comes into range of a reference ``R_pq`` with
status ``p != i``, a router is sent to the point that keeps both connected and maximizes local coverage: at
distance ``sqrt(r^2 - (a/2)^2)`` from the midpoint of ``R_ij R_pq`` (``a`` their distance), on the robot's side.
We use ``r = (1 - loss_margin) r_c`` instead of ``r_c`` so that the router, once there, is inside the range of
both references with the same safety band as the greedy deployment (exactly ``r_c`` would let rounding break
the links). Redundant triangles are avoided by one of three rules:

* ``off``: no triangular deployment at all (greedy only; an ablation, not in the paper);
* ``none``: no optimization, always deploy;
* ``global``: skip when ``R_ij`` and ``R_pq`` are already in one connected component of the deployed network
  (base nodes, deployed routers and routers on their way to a triangle goal — those already bridge the two);
* ``local``: skip when both ``R_ij`` and ``R_pq`` are flagged *disabled*; a triangular deployment flags both
  references and the new router.

In all modes no triangle is needed when ``R_ij`` and ``R_pq`` are within ``r_c`` of each other: they are
linked directly.
"""

from __future__ import annotations

import numpy as np

from amronet.algorithms.common.param_types import TriangularMode
from amronet.engine.network import components
from amronet.engine.radio import NeighbourTable

__all__ = ["TriangularMode", "select_triangles", "triangle_goal"]


def triangle_goal(p_i: np.ndarray, p_j: np.ndarray, side: np.ndarray, r: float) -> np.ndarray:
    """Goal points of triangular deployments.

    Args:
        p_i: Positions of the current references ``(M, 2)``.
        p_j: Positions of the references of the other status ``(M, 2)``.
        side: Positions of the deciding robots ``(M, 2)``; the goal lies on their side of the line ``p_i p_j``.
        r: Radius to stay within from both references.

    Returns:
        Goal points ``(M, 2)``; the midpoint where ``a > 2 r`` (no point is within ``r`` of both).
    """
    mid = 0.5 * (p_i + p_j)
    axis = p_j - p_i
    a = np.linalg.norm(axis, axis=1)
    normal = np.stack([-axis[:, 1], axis[:, 0]], axis=1) / np.maximum(a, 1e-12)[:, None]
    flip = np.einsum("ij,ij->i", side - mid, normal) < 0
    normal[flip] *= -1.0
    d = np.sqrt(np.clip(r * r - (0.5 * a) ** 2, 0.0, None))
    return mid + d[:, None] * normal


def select_triangles(
    mode: TriangularMode,
    deciders: np.ndarray,
    ref_i: np.ndarray,
    ref_j: np.ndarray,
    xy: np.ndarray,
    r_c: float,
    disabled: np.ndarray,
    table: NeighbourTable,
    committed: np.ndarray,
) -> np.ndarray:
    """Decide which candidate triangular deployments go ahead this step.

    Args:
        mode: ``none``, ``global`` or ``local``.
        deciders: Robots that met a reference of another status ``(M,)``.
        ref_i: Their current references ``(M,)``.
        ref_j: The references of the other status ``(M,)``.
        xy: All positions.
        r_c: Communication radius.
        disabled: Local-rule flags of all nodes (read only here).
        table: This step's neighbour table (its graph is read by the global rule only).
        committed: Nodes of the deployed network for the global rule (deployed nodes and triangle routers).

    Returns:
        Boolean mask ``(M,)`` of the deployments to perform. At most one per pair of references (or, with
        ``global``, per pair of components) goes ahead in one step: the lowest robot id.
    """
    m = len(deciders)
    go = np.linalg.norm(xy[ref_i] - xy[ref_j], axis=1) > r_c
    if mode == "local":
        go &= ~(disabled[ref_i] & disabled[ref_j])
        key_a, key_b = ref_i, ref_j
    elif mode == "global":
        _, labels = components(table, committed)
        key_a, key_b = labels[ref_i], labels[ref_j]
        go &= key_a != key_b
    else:
        key_a, key_b = ref_i, ref_j
    if not go.any():
        return go
    lo, hi = np.minimum(key_a, key_b), np.maximum(key_a, key_b)
    order = np.lexsort((deciders, hi, lo))
    order = order[go[order]]
    pair = np.stack([lo[order], hi[order]], axis=1)
    first = np.ones(len(order), dtype=bool)
    first[1:] = np.any(pair[1:] != pair[:-1], axis=1)
    out = np.zeros(m, dtype=bool)
    out[order[first]] = True
    return out
