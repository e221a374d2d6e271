"""The compiled search for a free spot next to an agent (:meth:`.releases.Releasing._release_spot`).

Every rounding is the NumPy form's (:func:`first_free_spot` gives its spots bit for bit): a distance is
``sqrt(dx * dx + dy * dy)`` (``np.linalg.norm(axis=...)`` of 2-vectors), and the dot products of the farther
rings' straight lines are those of the matrix product ``rel @ seg.T`` it took, which OpenBLAS computes with one
fused multiply-add (:func:`dot2`): the one of the second terms in a matrix-matrix product (or a single dot), the one
of the first terms in a matrix-vector product (one other body, or one candidate left).
"""

from __future__ import annotations

import math

from llvmlite import ir
from numba import njit
from numba.core import cgutils, types
from numba.extending import intrinsic

__all__ = ["dot2", "first_free_spot", "segment_gap"]


@intrinsic
def _fma(typingctx, a, b, c):  # pragma: no cover - numba
    """``a * b + c`` rounded once (LLVM's ``fma``: the CPU's instruction, or a correctly rounded software one)."""
    if not (a == types.float64 and b == types.float64 and c == types.float64):
        return None

    def codegen(context, builder, signature, args):
        fnty = ir.FunctionType(ir.DoubleType(), [ir.DoubleType()] * 3)
        fn = cgutils.get_or_insert_function(builder.module, fnty, "llvm.fma.f64")
        return builder.call(fn, args)

    return types.float64(types.float64, types.float64, types.float64), codegen


@njit(cache=True, inline="always")
def dot2(a0, a1, b0, b1, matrix_vector):  # pragma: no cover - numba
    """``a0 b0 + a1 b1`` rounded as the matrix product of the NumPy form (see the module's doc)."""
    if matrix_vector:
        return _fma(a0, b0, a1 * b1)
    return _fma(a1, b1, a0 * b0)


@njit(cache=True, inline="always")
def segment_gap(px, py, sx, sy, length2, x, y, matrix_vector):  # pragma: no cover - numba
    """Distance from ``(x, y)`` to the segment ``p -> p + s`` (``length2``: its squared length, at least 1e-300)."""
    t = dot2(x - px, y - py, sx, sy, matrix_vector) / length2
    if t < 0.0:
        t = 0.0
    elif t > 1.0:
        t = 1.0
    dx = x - (px + t * sx)
    dy = y - (py + t * sy)
    return math.sqrt(dx * dx + dy * dy)


@njit(cache=True)
def first_free_spot(cand, clear, n_near, px, py, ref_x, ref_y, within, r, xy, radius, agent):  # pragma: no cover
    """Index of the first free spot among the candidates, or -1 (the checks of the NumPy form, in its order).

    Args:
        cand: Candidate spots ``(M, 2)``: the ``n_near`` of the agent's own ring first, then the farther rings.
        clear: Whether the straight line from the agent to each candidate is clear of walls ``(M,)``.
        n_near: How many candidates are on the agent's own ring.
        px: The agent's x.
        py: The agent's y.
        ref_x: The reference's x.
        ref_y: The reference's y.
        within: How far from the reference a spot may be.
        r: The router's radius.
        xy: Every body's position ``(N, 2)``.
        radius: Every body's radius ``(N,)``.
        agent: The agent's index (not a body in the way).

    Returns:
        The first candidate of the agent's ring within ``within`` of the reference, clear of walls and of every
        body; else the first of the farther rings whose whole straight line passes clear of every body; else -1.
    """
    n = xy.shape[0]
    for i in range(n_near):
        dx = cand[i, 0] - ref_x
        dy = cand[i, 1] - ref_y
        if not (math.sqrt(dx * dx + dy * dy) <= within) or not clear[i]:
            continue
        free = True
        for j in range(n):
            if j == agent:
                continue
            ex = cand[i, 0] - xy[j, 0]
            ey = cand[i, 1] - xy[j, 1]
            if not (math.sqrt(ex * ex + ey * ey) >= r + radius[j]):
                free = False
                break
        if free:
            return i
    m = 0  # the farther candidates left to check against the bodies: the NumPy form's matrix product's columns
    for i in range(n_near, cand.shape[0]):
        dx = cand[i, 0] - ref_x
        dy = cand[i, 1] - ref_y
        if math.sqrt(dx * dx + dy * dy) <= within and clear[i]:
            m += 1
    matrix_vector = (n - 1 == 1) != (m == 1)
    for i in range(n_near, cand.shape[0]):
        dx = cand[i, 0] - ref_x
        dy = cand[i, 1] - ref_y
        if not (math.sqrt(dx * dx + dy * dy) <= within) or not clear[i]:
            continue
        sx = cand[i, 0] - px
        sy = cand[i, 1] - py
        length2 = max(sx * sx + sy * sy, 1e-300)
        free = True
        for j in range(n):
            if j == agent:
                continue
            if not (segment_gap(px, py, sx, sy, length2, xy[j, 0], xy[j, 1], matrix_vector) >= r + radius[j]):
                free = False
                break
        if free:
            return i
    return -1
