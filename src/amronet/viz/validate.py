"""Checks of the arrays the pictures are drawn from: shapes, dtypes and allowed values, with clear messages."""

from __future__ import annotations

import math

import numpy as np

__all__ = ["KINDS", "STATES", "check_mask", "validate_nodes"]

KINDS: tuple[str, ...] = ("base", "router", "agent")
"""Allowed values of the ``kind`` array."""

STATES: tuple[str, ...] = ("base", "explore", "reference", "triangle", "triangle-settled", "agent", "dropped",
                             "failed", "relocating", "strip")
"""Allowed values of the ``state`` array."""


def check_mask(name: str, mask: np.ndarray | None, shape: tuple[int, int]) -> np.ndarray | None:
    """Return ``mask`` as a boolean array of ``shape``, or raise ``ValueError`` naming it."""
    if mask is None:
        return None
    mask = np.asarray(mask)
    if mask.shape != tuple(shape):
        raise ValueError(f"{name} must have the map's shape {tuple(shape)}, got {mask.shape}")
    if mask.dtype != np.bool_:
        raise ValueError(f"{name} must be a boolean mask, got dtype {mask.dtype}")
    return mask


def validate_nodes(
    xy: np.ndarray, kind: np.ndarray, state: np.ndarray, status: np.ndarray, links: np.ndarray, r_c: float
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Check the node arrays' shapes and values; return them as NumPy arrays."""
    xy = np.asarray(xy, dtype=float)
    if xy.size == 0:
        xy = xy.reshape(0, 2)
    if xy.ndim != 2 or xy.shape[1] != 2:
        raise ValueError(f"xy must have shape (N, 2), got {xy.shape}")
    if not np.all(np.isfinite(xy)):
        raise ValueError("xy must be finite")
    n = xy.shape[0]
    kind = np.asarray(kind, dtype=str)
    state = np.asarray(state, dtype=str)
    status = np.asarray(status)
    for name, arr in (("kind", kind), ("state", state), ("status", status)):
        if arr.shape != (n,):
            raise ValueError(f"{name} must have shape ({n},) like xy, got {arr.shape}")
    for name, arr, allowed in (("kind", kind, KINDS), ("state", state, STATES)):
        bad = sorted(set(arr.tolist()) - set(allowed))
        if bad:
            raise ValueError(f"{name} has unknown values {bad}; allowed: {list(allowed)}")
    if n and not np.issubdtype(status.dtype, np.integer):
        raise ValueError(f"status must be integer, got dtype {status.dtype}")
    status = status.astype(np.int64)
    links = np.asarray(links)
    if links.size == 0:
        links = links.reshape(0, 2).astype(np.int64)
    if links.ndim != 2 or links.shape[1] != 2:
        raise ValueError(f"links must have shape (M, 2), got {links.shape}")
    if not np.issubdtype(links.dtype, np.integer):
        raise ValueError(f"links must be integer indices, got dtype {links.dtype}")
    if links.size and (links.min() < 0 or links.max() >= n):
        raise ValueError(f"links must index xy's {n} rows, got values in [{links.min()}, {links.max()}]")
    if not (math.isfinite(r_c) and r_c > 0):
        raise ValueError(f"r_c must be a positive finite number, got {r_c}")
    return xy, kind, state, status, links
