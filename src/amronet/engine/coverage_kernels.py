"""The raster coverage count in numba: the disks' cells painted into a bitset, then counted under the mask's bits.

Cell ``(i, j)`` of a map with origin ``(ox, oy)`` and resolution ``res`` has its centre at
``(cx, cy) = (ox + (j + 0.5) * res, oy + (i + 0.5) * res)`` and is covered by the disk of radius ``r`` around ``(x, y)``
when ``(cx - x)**2 + (cy - y)**2 <= r**2`` (evaluated exactly this way in float64).

How it is counted:

1. For every node, the column interval of the covered cell centres in each row its disk spans, in closed form: with
   ``dy = cy - y``, the centres within ``sqrt(r**2 - dy**2)`` of ``x``. This pass runs over the node's rows without a
   branch, so the compiler turns it into vector instructions (four rows at a time). An interval end that falls within
   a generous tolerance (10**6 times the float64 rounding error) of a cell centre is flagged, and the cell-centre test
   above decides it.
2. Each interval is painted into a bitset of the rows (64 columns to a word): a union with no sorting and no merging.
3. The covered cells that count are the set bits of the bitset ANDed with the mask's bits (one population count per
   word).

Per node and row this is a few dozen instructions; painting and counting touch ``ncols / 64`` words per row. A batch
of runs (:func:`scan_runs`) counts, for each run, the cells of its covering nodes and of those linked to a base
station: when the linked nodes are among the covering ones (as they are by construction), the linked ones are painted
and counted first and the rest added to the same bitset, so no node is painted twice.
"""

from __future__ import annotations

import math

import numpy as np
from llvmlite import ir
from numba import njit
from numba import uint64 as _u
from numba.core import cgutils, types
from numba.extending import intrinsic

__all__ = ["mask_words", "scan", "scan_runs"]

_ALL = np.uint64(0xFFFF_FFFF_FFFF_FFFF)
_ONE = np.uint64(1)


@intrinsic
def _popcount(typingctx, x):  # pragma: no cover - numba
    """The number of set bits of a uint64 (LLVM's ``ctpop``: one instruction where the CPU has it)."""
    if x != types.uint64:
        return None

    def codegen(context, builder, signature, args):
        fnty = ir.FunctionType(ir.IntType(64), [ir.IntType(64)])
        fn = cgutils.get_or_insert_function(builder.module, fnty, "llvm.ctpop.i64")
        return builder.call(fn, args)

    return types.uint64(types.uint64), codegen


def mask_words(mask: np.ndarray) -> np.ndarray:
    """A boolean ``(rows, cols)`` mask as bits: ``(rows, ceil(cols / 64))`` uint64, column ``j`` at bit ``j % 64``."""
    rows, cols = mask.shape
    padded = np.zeros((rows, -(-cols // 64) * 64), dtype=bool)
    padded[:, :cols] = mask
    return np.ascontiguousarray(np.packbits(padded, axis=1, bitorder="little").view("<u8").astype(np.uint64))


@njit(cache=True, inline="always")
def _inside(j, x, dy2, r2, ox, res):  # pragma: no cover - numba
    dx = ox + (j + 0.5) * res - x
    return dx * dx + dy2 <= r2


@njit(cache=True, inline="always")
def _row_intervals(x, y, r, ox, oy, res, ncols, i0, nr, lo_out, hi_out, flags):  # pragma: no cover - numba
    """Step 1 for one node and its rows ``i0 .. i0 + nr - 1``: interval ends (as floats) and flags.

    ``flags``: 0 the row has no cell of the disk, bit 0 it may have, bit 1 the low end and bit 2 the high end need the
    cell-centre test.
    """
    r2 = r * r
    inv = 1.0 / res
    t1 = 1e-9 * (r / res) * r
    u = (x - ox) * inv - 0.5
    tp = 1e-9 * (1.0 + (abs(x) + abs(ox) + r) * inv)
    fcols = float(ncols)
    for k in range(nr):
        dy = oy + (i0 + k + 0.5) * res - y
        dy2 = dy * dy
        hw = math.sqrt(max(r2 - dy2, 0.0))
        hwc = hw * inv
        flo = u - hwc
        fhi = u + hwc
        jlo = np.ceil(max(flo, 0.0))
        jhi = np.floor(min(fhi, fcols - 1.0))
        tol = tp * hw + t1
        low = min(jlo - flo, flo - jlo + 1.0) * hw < tol
        high = min(fhi - jhi, jhi + 1.0 - fhi) * hw < tol
        # (no flag on a row without the disk: its ends may be far outside the map, too far to be integers)
        f = 0 if (dy2 > r2 or flo > fcols or fhi < -1.0) else 1 + 2 * low + 4 * high
        lo_out[_u(k)] = jlo
        hi_out[_u(k)] = jhi
        flags[_u(k)] = f


@njit(cache=True, inline="always")
def _node_rows(y, r, oy, res, nrows):  # pragma: no cover - numba
    """The rows ``(i0, nr)`` the node's disk may reach (a row either side to spare); ``nr = 0`` for none."""
    rc = r / res
    v = (y - oy) / res - 0.5
    lo = max(v - rc - 1.0, 0.0)  # clipped to the map before they become integers (a disk may be far larger)
    hi = min(v + rc + 1.0, nrows - 1.0)
    if hi < lo:
        return 0, 0
    i0 = int(np.floor(lo))
    return i0, int(np.ceil(hi)) - i0 + 1


@njit(cache=True)
def _paint(xy, nodes, r, ox, oy, res, ncols, words, lo_buf, hi_buf, flags, touched):  # pragma: no cover - numba
    """Paint the cells of the disks around ``xy[nodes]`` into ``words``; widen ``touched`` ``[first, last]`` row."""
    nrows = words.shape[0]
    r2 = r * r
    for q in range(nodes.shape[0]):
        x = xy[nodes[q], 0]
        y = xy[nodes[q], 1]
        i0, nr = _node_rows(y, r, oy, res, nrows)
        if nr == 0:
            continue
        _row_intervals(x, y, r, ox, oy, res, ncols, i0, nr, lo_buf, hi_buf, flags)
        for k in range(nr):
            f = flags[k]
            if f == 0:
                continue
            i = i0 + k
            jlo = int(lo_buf[k])
            jhi = int(hi_buf[k])
            if f > 1:
                dy = oy + (i + 0.5) * res - y
                dy2 = dy * dy
                if f & 2:
                    while jlo > 0 and _inside(jlo - 1, x, dy2, r2, ox, res):
                        jlo -= 1
                    while jlo <= jhi and not _inside(jlo, x, dy2, r2, ox, res):
                        jlo += 1
                if f & 4:
                    while jhi < ncols - 1 and _inside(jhi + 1, x, dy2, r2, ox, res):
                        jhi += 1
                    while jhi >= jlo and not _inside(jhi, x, dy2, r2, ox, res):
                        jhi -= 1
            if jlo > jhi:
                continue
            touched[0] = min(touched[0], i)
            touched[1] = max(touched[1], i)
            w0 = jlo >> 6
            w1 = jhi >> 6
            low = _ALL << np.uint64(jlo & 63)
            high = _ALL >> np.uint64(63 - (jhi & 63))
            if w0 == w1:
                words[i, w0] |= low & high
            else:
                words[i, w0] |= low
                for w in range(w0 + 1, w1):
                    words[i, w] = _ALL
                words[i, w1] |= high


@njit(cache=True)
def _count(words, mask, touched, clear):  # pragma: no cover - numba
    """Set bits of ``words & mask`` in the ``touched`` rows; with ``clear``, those rows are zeroed after."""
    total = 0
    for i in range(touched[0], touched[1] + 1):
        for w in range(words.shape[1]):
            total += _popcount(words[i, w] & mask[i, w])
            if clear:
                words[i, w] = 0
    return total


@njit(cache=True, inline="always")
def _scratch(r, res, nrows, nw):  # pragma: no cover - numba
    """A zeroed bitset of the map and the row buffers of one node (its disk spans at most ``2 r / res + 5`` rows)."""
    span = 2.0 * (r / res) + 6.0
    n = nrows if span >= nrows else int(span)
    return np.zeros((nrows, nw), np.uint64), np.empty(n), np.empty(n), np.empty(n, np.int64)


@njit(cache=True)
def scan(xy, r, ox, oy, res, mask, ncols, out, paint):  # pragma: no cover - numba
    """The mask cells the disks of radius ``r`` around ``xy`` ``(N, 2)`` cover; -1 if ``xy`` is not finite.

    ``mask``: the mask's bits (:func:`mask_words`) of a map ``ncols`` wide. With ``paint``, the covered mask cells are
    also set in ``out`` (boolean, the map's shape).
    """
    n = xy.shape[0]
    for k in range(n):
        if not (np.isfinite(xy[k, 0]) and np.isfinite(xy[k, 1])):
            return -1
    nrows = mask.shape[0]
    words, lo_buf, hi_buf, flags = _scratch(r, res, nrows, mask.shape[1])
    touched = np.array([nrows, -1])
    _paint(xy, np.arange(n), r, ox, oy, res, ncols, words, lo_buf, hi_buf, flags, touched)
    if paint:
        for i in range(touched[0], touched[1] + 1):
            for j in range(ncols):
                if (words[i, j >> 6] & mask[i, j >> 6]) >> np.uint64(j & 63) & _ONE:
                    out[i, j] = True
    return _count(words, mask, touched, np.bool_(False))


@njit(cache=True)
def scan_runs(xy, network, linked, starts, stops, r, ox, oy, res, mask, ncols, counts):  # pragma: no cover - numba
    """Per run ``k`` (rows ``starts[k]:stops[k]``), the mask cells its ``network`` and its ``linked`` nodes cover.

    Into ``counts[k]``, as :func:`scan` counts them; ``False`` when a position of such a node is not finite.
    """
    nrows = mask.shape[0]
    words, lo_buf, hi_buf, flags = _scratch(r, res, nrows, mask.shape[1])
    touched = np.empty(2, np.int64)
    first = np.empty(xy.shape[0], np.int64)
    then = np.empty(xy.shape[0], np.int64)
    for k in range(starts.shape[0]):
        nf = 0
        nt = 0
        subset = True
        for q in range(starts[k], stops[k]):
            if network[q] or linked[q]:
                if not (np.isfinite(xy[q, 0]) and np.isfinite(xy[q, 1])):
                    return False
            if linked[q] and not network[q]:
                subset = False
        for q in range(starts[k], stops[k]):  # the linked nodes first, then the other covering ones
            if linked[q]:
                first[nf] = q
                nf += 1
            elif network[q]:
                then[nt] = q
                nt += 1
        touched[0] = nrows
        touched[1] = -1
        if subset:
            _paint(xy, first[:nf], r, ox, oy, res, ncols, words, lo_buf, hi_buf, flags, touched)
            counts[k, 1] = _count(words, mask, touched, np.bool_(nt == 0))
            if nt == 0:
                counts[k, 0] = counts[k, 1]
                continue
            _paint(xy, then[:nt], r, ox, oy, res, ncols, words, lo_buf, hi_buf, flags, touched)
            counts[k, 0] = _count(words, mask, touched, np.bool_(True))
            continue
        # linked nodes outside the network (not what a loop gives): one count after the other
        _paint(xy, first[:nf], r, ox, oy, res, ncols, words, lo_buf, hi_buf, flags, touched)
        counts[k, 1] = _count(words, mask, touched, np.bool_(True))
        nt = 0
        for q in range(starts[k], stops[k]):
            if network[q]:
                then[nt] = q
                nt += 1
        touched[0] = nrows
        touched[1] = -1
        _paint(xy, then[:nt], r, ox, oy, res, ncols, words, lo_buf, hi_buf, flags, touched)
        counts[k, 0] = _count(words, mask, touched, np.bool_(True))
    return True
