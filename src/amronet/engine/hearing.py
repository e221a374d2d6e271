"""Where a receiver would hear the nodes: a link's margin kernel, and the kernels of coverage and signal maps.

A map cell is *heard* from a node when a receiver at the cell's centre would get the node's signal at or above
the usable threshold: the model's margin (dB over the threshold) of the link from the node to the centre is
``>= 0``. Coverage under a radio model generalises Eq. (1): the fraction of the area that counts whose cells are
heard from some node. The signal map is the best margin (and so RSSI) per cell.

**The margin kernel** of a model is one compiled function ``margin(xa, ya, xb, yb, d, sa, sb, floor_db, h)``: the
margin of the link from ``(xa, ya)`` to ``(xb, yb)``, ``d`` apart, whose ends see the shadowing field values ``sa``
and ``sb`` (0 without shadowing), for the radio's :class:`HearingInputs` ``h`` (its link budget, the map's walls,
the shadowing field). It may return any number below ``floor_db`` when the margin is below ``floor_db`` (the
path-loss law stops counting walls there). It must be symmetric, and depend on the two points and ``h`` alone: the
link table, coverage and the signal map all apply it (:mod:`amronet.engine.margin_kernels`).
:func:`path_loss_margin` is the law of the three built-in models (:mod:`amronet.engine.propagation`): distance,
walls crossed (:mod:`amronet.engine.walls`), shadowing (:mod:`amronet.engine.shadowing`).

**A margin bound** (optional) ``bound(d, s, h)``: an upper bound of the margin of every link at least ``d`` long
whose ends' field values sum to at most ``s``. The kernels skip blocks of :data:`BLOCK` cells whose bound is below what
they look for; without one (:func:`no_bound`) they test every cell within reach.

The kernels below call ``model_margin`` and ``model_bound``, here the path-loss law's;
:func:`amronet.engine.margin_kernels.margin_kernels` compiles copies of them that call another model's.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numba import njit

from amronet.engine.cell_boxes import BLOCK, Cells, block_gap, cells_of, named_cells, node_box
from amronet.engine.kernel_data import Grid
from amronet.engine.occlusion import BINS, NEAR, dark, look, shade
from amronet.engine.propagation import MIN_DISTANCE_M, LinkBudget
from amronet.engine.shadowing import FieldGrid, ShadowingField, field_at, link_shadowing
from amronet.engine.wall_bits import box_clear_bits, count_walls_bits, wall_bits
from amronet.engine.walls import wall_grid
from amronet.world.occupancy import OccupancyMap

__all__ = ["BLOCK", "Cells", "HearingInputs", "best_margin_grid", "cells_of", "heard_cells",
           "named_inputs", "no_bound", "node_reach", "open_margin", "path_loss_bound", "path_loss_margin",
           "wall_limit"]


def _frozen(a: np.ndarray) -> np.ndarray:
    a.flags.writeable = False
    return a


# The stand-ins of a radio without walls or shadowing have the dtypes and the read-only flag of the real grids
# (:func:`~amronet.engine.walls.wall_grid`, :class:`~amronet.engine.shadowing.ShadowingField`): numba compiles one
# version of each kernel per argument type, so every radio model then shares one compiled kernel.
_NO_WALLS = _frozen(np.zeros((0, 0), np.uint8))
_NO_JUMP = _frozen(np.zeros((0, 0), np.float32))
_NO_SHADOW = _frozen(np.zeros((1, 1)))
_NO_BITS = _frozen(np.zeros((2, 0, 0), np.uint64))


class HearingInputs(NamedTuple):
    """A radio's parameters as the margin kernels read them; built by :meth:`from_budget`."""

    r_c: float
    """The calibrated range: a median link without walls this long is at the threshold (m)."""
    n10: float
    """Ten times the path-loss exponent."""
    wall_db: float
    """Loss per wall crossed (dB); 0 when the model ignores walls."""
    walls: Grid
    """The map's wall grid (:func:`~amronet.engine.walls.wall_grid`): ``blocked`` its wall cells, ``clear`` the safe
    jumps; 0x0 without walls."""
    field: FieldGrid
    """The shadowing field; a 1x1 zero grid without shadowing."""
    corr: float
    """The shadowing's decorrelation distance (m)."""
    clip: float
    """The largest shadowing of a link (dB); 0 without shadowing."""
    wall_bits: np.ndarray
    """The map's bit grids of wall cells and of where the walk leaps (:func:`~amronet.engine.wall_bits.wall_bits`):
    what the walk and the box test read; ``(2, 0, 0)`` without walls."""

    @classmethod
    def from_budget(cls, budget: LinkBudget, omap: OccupancyMap | None, field: ShadowingField | None,
                    walls: bool = True) -> HearingInputs:
        """The inputs of ``budget``; walls come from ``omap`` when ``walls`` and ``budget.wall_db > 0``."""
        use_walls = walls and budget.wall_db > 0 and omap is not None
        cells, jump = wall_grid(omap) if use_walls else (_NO_WALLS, _NO_JUMP)
        bits = wall_bits(omap) if use_walls else _NO_BITS
        ox, oy = (float(omap.origin[0]), float(omap.origin[1])) if omap is not None else (0.0, 0.0)
        res = float(omap.resolution) if omap is not None else 1.0
        grid = FieldGrid(_NO_SHADOW, 0.0, 0.0, 1.0) if field is None else field.kernel_grid
        return cls(float(budget.r_c), 10.0 * budget.exponent, float(budget.wall_db) if use_walls else 0.0,
                   Grid(cells, jump, ox, oy, res), grid, float(budget.shadowing_corr_m),
                   0.0 if field is None else budget.shadowing_clip * budget.shadowing_db, bits)

    def plain(self) -> tuple:
        """The inputs as the kernels take them: a plain tuple in the fields' order, ``walls`` and ``field`` too.

        numba dispatches a plain tuple four times faster than a named one (0.5 against 2.2 microseconds); the
        kernels name it again (:func:`named_inputs`) before they hand it to a margin kernel.
        """
        return (self.r_c, self.n10, self.wall_db, tuple(self.walls), tuple(self.field), self.corr, self.clip,
                self.wall_bits)


@njit(cache=True, inline="always")
def named_inputs(t):  # pragma: no cover - numba
    """The :class:`HearingInputs` of its :meth:`~HearingInputs.plain` tuple (in compiled code: no cost)."""
    r_c, n10, wall_db, walls, field, corr, clip, bits = t
    return HearingInputs(r_c, n10, wall_db, Grid(walls[0], walls[1], walls[2], walls[3], walls[4]),
                         FieldGrid(field[0], field[1], field[2], field[3]), corr, clip, bits)


@njit(cache=True, inline="always")
def path_loss_margin(xa, ya, xb, yb, d, sa, sb, floor_db, h):  # pragma: no cover - numba
    """The link budget's margin (dB over the threshold) of the link ``a -> b`` of length ``d`` (see module doc).

    Walls are counted only while the margin can stay above ``floor_db``: a result below ``floor_db`` is a bound,
    not the exact margin (``floor_db = 0`` decides usability; the signal map passes its display floor).
    """
    m = open_margin(d, sa, sb, h.r_c, h.n10, h.corr, h.clip)
    if h.wall_db > 0.0 and m >= floor_db:
        m -= h.wall_db * walls_crossed(xa, ya, xb, yb, wall_limit(m, floor_db, h.wall_db), h)
    return m


@njit(cache=True, inline="always")
def open_margin(d, sa, sb, r_c, n10, corr, clip):  # pragma: no cover - numba
    """:func:`path_loss_margin` before walls: distance and shadowing (the inputs' fields, read by the caller)."""
    m = n10 * math.log10(r_c / max(d, MIN_DISTANCE_M))
    if clip > 0.0:
        m += link_shadowing(sa, sb, d, corr, clip)
    return m


@njit(cache=True, inline="always")
def wall_limit(m, floor_db, wall_db):  # pragma: no cover - numba
    """The walls :func:`path_loss_margin` counts at most of a link whose margin before walls is ``m``, plus one."""
    return int(math.floor((m - floor_db) / wall_db)) + 1


@njit(cache=True, inline="always")
def walls_crossed(xa, ya, xb, yb, limit, h):  # pragma: no cover - numba
    """Walls crossed by the segment ``a -> b`` on the radio's map ``h``, counting stopped above ``limit``.

    :func:`~amronet.engine.walls.count_walls`, or 0 at once where the rectangle of cells between the two ends holds
    no wall (:func:`~amronet.engine.walls.box_clear`: the walk's own answer, without the walk); both asked of the
    map's bit grids (:mod:`amronet.engine.wall_bits`). A model's margin kernel that counts walls calls this.
    """
    w = h.walls
    bits = h.wall_bits
    if box_clear_bits(bits, w.blocked.shape[1], w.ox, w.oy, w.res, xa, ya, xb, yb):
        return 0
    return count_walls_bits(bits, w.blocked, w.clear, w.ox, w.oy, w.res, xa, ya, xb, yb, limit)


@njit(cache=True, inline="always")
def _shadow_bound(v, clip):  # pragma: no cover - numba
    """Largest link shadowing of two field values summing to ``v``: ``sqrt(2 (1 + rho))`` is in [sqrt 2, 2]."""
    b = v / math.sqrt(2.0) if v >= 0.0 else v / 2.0
    return min(max(b, -clip), clip)


@njit(cache=True, inline="always")
def path_loss_bound(d, s, h):  # pragma: no cover - numba
    """Upper bound of :func:`path_loss_margin` over links at least ``d`` long whose field values sum to ``<= s``."""
    up = h.n10 * math.log10(h.r_c / max(d, MIN_DISTANCE_M))
    if h.clip > 0.0:
        up += _shadow_bound(s, h.clip)
    return up


@njit(cache=True, inline="always")
def no_bound(d, s, h):  # pragma: no cover - numba
    """The bound of a model that gives none: nothing is skipped."""
    return math.inf


model_margin = path_loss_margin
"""The margin kernel the kernels below call (a model's own in the copies of
:mod:`amronet.engine.margin_kernels`)."""
model_bound = path_loss_bound
"""The margin bound the kernels below call."""
SHADE_AFTER = 256
"""A node's wall shadows and clear lines (:mod:`amronet.engine.occlusion`) are drawn once it has asked this many
cells about walls: a node that would walk few cells does not pay for them."""
model_is_path_loss = True
"""Whether ``model_margin`` is :func:`path_loss_margin`: then :func:`heard_cells` skips the wall walk of a cell on a
clear line from the node (no wall) and of a cell whose budget allows no wall and that lies in a wall's shadow
(:mod:`amronet.engine.occlusion`): the walk's answers."""


@njit(cache=True, inline="always")
def _heard_within2(s, h):  # pragma: no cover - numba
    """Squared length past which :func:`path_loss_bound` is below 0 for field values summing to ``<= s``.

    A relative 1e-9 to spare: no cell farther from the node is heard (:func:`_mark_node` skips it unasked).
    """
    far = h.r_c * 10.0 ** (_shadow_bound(s, h.clip) / h.n10) if h.clip > 0.0 else h.r_c
    return far * far * (1.0 + 1e-9)


@njit(cache=True)
def node_reach(s, reach, h):  # pragma: no cover - numba
    """A distance ``<= reach`` past which the margin bound of links whose ends' field values sum to ``<= s`` is below 0.

    ``reach`` itself when the bound there is not below 0 (or there is no bound); else found by bisection: no cell
    farther from a node is heard (the bound holds over every link at least that long).
    """
    if not model_bound(reach, s, h) < 0.0:
        return reach
    lo, hi = 0.0, reach
    for _ in range(40):
        mid = 0.5 * (lo + hi)
        if model_bound(mid, s, h) < 0.0:
            hi = mid
        else:
            lo = mid
    return hi


@njit(cache=True, inline="always")
def _in_shadow(x, y, cells, bi, bj, rows, cols, lit, shadows, near2):  # pragma: no cover - numba
    """Whether every cell centre of block ``(bi, bj)`` lies in a wall's shadow of ``(x, y)`` (:func:`dark`)."""
    i0, j0 = bi * BLOCK, bj * BLOCK
    i1, j1 = min(i0 + BLOCK - 1, rows - 1), min(j0 + BLOCK - 1, cols - 1)
    return dark(lit, shadows, cells.ox + (j0 + 0.5) * cells.res - x, cells.ox + (j1 + 0.5) * cells.res - x,
                cells.oy + (i0 + 0.5) * cells.res - y, cells.oy + (i1 + 0.5) * cells.res - y, near2)


@njit(cache=True)
def _mark_node(x, y, mask, cells, reach, out, owner, key, window, h, top_field, blocks):  # pragma: no cover - numba
    """Mark ``out[i, j]`` for the ``mask`` cells ``(i, j)`` of ``window`` heard from the node at ``(x, y)``.

    Cells already marked are skipped; with an ``owner`` grid (not 0x0) a newly marked cell's owner is ``key``.
    ``window``: the cells ``(i0, i1, j0, j1)`` looked at; ``top_field``: the largest of ``cells.block_field``;
    ``blocks``: as :func:`heard_cells` takes it. Returns how many were newly marked.
    """
    rows, cols = mask.shape
    total = 0
    owned = owner.shape[0] > 0
    shadowed = h.clip > 0.0
    i0, i1, j0, j1 = node_box(x, y, reach, cells, rows, cols)
    i0, i1, j0, j1 = max(i0, window[0]), min(i1, window[1]), max(j0, window[2]), min(j1, window[3])
    if i0 > i1 or j0 > j1:
        return 0
    sa = field_at(h.field, x, y) if shadowed else 0.0
    far = math.sqrt(max(x - cells.ox, cells.ox + cols * cells.res - x) ** 2
                    + max(y - cells.oy, cells.oy + rows * cells.res - y) ** 2) + cells.res  # past every cell
    near_reach = node_reach(sa + top_field if shadowed else 0.0, min(reach, far), h)
    if near_reach < reach:  # the node's own reach: a smaller box, fewer walls to shade
        reach = near_reach
        i0, i1, j0, j1 = node_box(x, y, reach, cells, rows, cols)
        i0, i1, j0, j1 = max(i0, window[0]), min(i1, window[1]), max(j0, window[2]), min(j1, window[3])
        if i0 > i1 or j0 > j1:
            return 0
    at_cell, at_block = cells.field, cells.block_field  # out of the loops (see candidate_margins)
    walled = h.wall_db > 0.0
    shadows = np.empty(BINS if model_is_path_loss and walled else 0)
    lit = np.empty(BINS if model_is_path_loss and walled else 0)
    asked = 0  # cells asked about walls: the shadows and clear lines are drawn after SHADE_AFTER of them
    near2 = (NEAR * h.walls.res) ** 2
    kept = blocks.shape[0] > 0
    for bi in range(i0 // BLOCK, i1 // BLOCK + 1):
        for bj in range(j0 // BLOCK, j1 // BLOCK + 1):
            if kept and blocks[bi, bj] == 0:  # no cell left to decide
                continue
            gap = block_gap(x, y, cells, bi, bj, rows, cols)
            if gap > reach:
                continue
            up = model_bound(gap, sa + at_block[bi, bj] if shadowed else 0.0, h)
            if up < 0.0:
                continue
            far2 = _heard_within2(sa + at_block[bi, bj] if shadowed else 0.0, h) if model_is_path_loss else math.inf
            dim = model_is_path_loss and walled and up < h.wall_db - 1e-9  # no cell of the block allows a wall
            if dim and asked >= SHADE_AFTER and _in_shadow(x, y, cells, bi, bj, rows, cols, lit, shadows, near2):
                continue  # every cell of the block in a wall's shadow: none heard
            ia, ib = max(bi * BLOCK, i0), min(bi * BLOCK + BLOCK, i1 + 1)
            ja, jb = max(bj * BLOCK, j0), min(bj * BLOCK + BLOCK, j1 + 1)
            left = 0  # the block's mask cells still not marked
            for i in range(ia, ib):
                cy = cells.oy + (i + 0.5) * cells.res
                for j in range(ja, jb):
                    if not mask[i, j] or out[i, j]:
                        continue
                    left += 1
                    cx = cells.ox + (j + 0.5) * cells.res
                    dd = (cx - x) * (cx - x) + (cy - y) * (cy - y)
                    if dd > far2:  # past the block's bound: not heard
                        continue
                    sight = 2  # once the shadows are drawn: 1 a clear line, -1 in a wall's shadow, 0 neither; 2 unasked
                    if dim and asked >= SHADE_AFTER:  # a cell in a wall's shadow needs no margin
                        sight = look(lit, shadows, cx - x, cy - y, dd, near2)
                        if sight < 0:
                            continue
                    d = math.sqrt(dd)
                    if d > reach:
                        continue
                    sb = at_cell[i, j] if shadowed else 0.0
                    if model_is_path_loss:  # path_loss_margin written out, a shadowed cell's walk skipped
                        m = open_margin(d, sa, sb, h.r_c, h.n10, h.corr, h.clip)
                        if walled and m >= 0.0:
                            if asked < SHADE_AFTER:
                                m -= h.wall_db * walls_crossed(x, y, cx, cy, wall_limit(m, 0.0, h.wall_db), h)
                                asked += 1
                                if asked == SHADE_AFTER:
                                    shade(x, y, reach, h.wall_bits, h.walls.blocked.shape[1], h.walls.ox,
                                          h.walls.oy, h.walls.res, shadows, lit)
                            else:
                                if sight == 2:
                                    sight = look(lit, shadows, cx - x, cy - y, dd, near2)
                                if sight < 0 and m < h.wall_db:
                                    continue  # no wall allowed, and in a wall's shadow: not heard
                                if sight != 1:  # a wall may be on the way
                                    m -= h.wall_db * walls_crossed(x, y, cx, cy, wall_limit(m, 0.0, h.wall_db), h)
                    else:
                        m = model_margin(x, y, cx, cy, d, sa, sb, 0.0, h)
                    if m >= 0.0:
                        out[i, j] = True
                        if owned:
                            owner[i, j] = key
                        total += 1
                        left -= 1
            if kept and left == 0 and ia == bi * BLOCK and ib == min(bi * BLOCK + BLOCK, rows) \
                    and ja == bj * BLOCK and jb == min(bj * BLOCK + BLOCK, cols):  # the whole block looked at
                blocks[bi, bj] = 0
    return total


@njit(cache=True)
def heard_cells(xy, keys, mask, grid, reach, covered, owner, window, hearing, blocks):  # pragma: no cover - numba
    """Mark in ``covered`` the ``mask`` cells heard from a node of ``xy``; return how many were newly marked.

    ``grid``: the :class:`Cells` (:func:`cells_of`) and ``hearing`` the :class:`HearingInputs`, as plain tuples;
    cells already marked are skipped; no link is longer than ``reach``. Only the cells of ``window``
    ``(i0, i1, j0, j1)`` are looked at (a node whose box misses it costs nothing). With an ``owner`` grid (int32,
    not 0x0), a cell newly marked from ``xy[k]`` gets the owner ``keys[k]`` (``keys`` may be empty without one).
    ``blocks`` (uint8, one per block of :data:`BLOCK` cells a side, or 0x0 for none): 0 where a block holds no
    ``mask`` cell left unmarked in ``covered`` (its cells are not looked at); set to 0 where a pass finds that so.
    Each cell's decision depends on the node and the cell alone: the union marked is the same in any order, over
    any split of the nodes into calls.
    """
    cells, h = named_cells(grid), named_inputs(hearing)
    owned = owner.shape[0] > 0
    total = 0
    top_field = cells.block_field.max()
    for k in range(xy.shape[0]):
        key = keys[k] if owned else np.int32(-1)
        total += _mark_node(xy[k, 0], xy[k, 1], mask, cells, reach, covered, owner, key, window, h, top_field,
                            blocks)
    return total


@njit(cache=True)
def best_margin_grid(xy, grid, out, floor_db, reach, hearing):  # pragma: no cover - numba
    """``out[i, j]``: the best margin over the nodes ``xy`` at the centre of cell ``(i, j)``.

    Only margins at or above ``floor_db`` are written (cells below it keep their value; fill ``out`` with ``-inf``
    first); no margin at or above ``floor_db`` is farther than ``reach`` (which may be infinite). ``grid`` and
    ``hearing`` as for :func:`heard_cells`.
    """
    cells, h = named_cells(grid), named_inputs(hearing)
    rows, cols = out.shape
    shadowed = h.clip > 0.0
    at_cell, at_block = cells.field, cells.block_field  # out of the loops (see candidate_margins)
    for k in range(xy.shape[0]):
        x = xy[k, 0]
        y = xy[k, 1]
        sa = field_at(h.field, x, y) if shadowed else 0.0
        i0, i1, j0, j1 = node_box(x, y, reach, cells, rows, cols)
        if i0 > i1 or j0 > j1:
            continue
        for bi in range(i0 // BLOCK, i1 // BLOCK + 1):
            for bj in range(j0 // BLOCK, j1 // BLOCK + 1):
                gap = block_gap(x, y, cells, bi, bj, rows, cols)
                if model_bound(gap, sa + at_block[bi, bj] if shadowed else 0.0, h) < floor_db:
                    continue
                for i in range(max(bi * BLOCK, i0), min(bi * BLOCK + BLOCK, i1 + 1)):
                    cy = cells.oy + (i + 0.5) * cells.res
                    for j in range(max(bj * BLOCK, j0), min(bj * BLOCK + BLOCK, j1 + 1)):
                        cx = cells.ox + (j + 0.5) * cells.res
                        d = math.sqrt((cx - x) * (cx - x) + (cy - y) * (cy - y))
                        if d > reach:
                            continue
                        sb = at_cell[i, j] if shadowed else 0.0
                        upper = model_bound(d, sa + sb, h)
                        if upper <= out[i, j] or upper < floor_db:
                            continue
                        m = model_margin(x, y, cx, cy, d, sa, sb, max(floor_db, out[i, j]), h)
                        if m >= floor_db and m > out[i, j]:
                            out[i, j] = m
