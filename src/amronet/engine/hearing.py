"""Where a receiver would hear the nodes: the compiled kernels behind coverage and signal maps of any radio.

A map cell is *heard* from a node when a receiver at the cell's centre would get the node's signal at or above
the usable threshold: its margin (:mod:`amronet.engine.propagation`) over the link from the node to the centre,
with the walls that link crosses (:mod:`amronet.engine.walls`) and its shadowing
(:mod:`amronet.engine.shadowing`), is ``>= 0``. Coverage under a radio model generalises Eq. (1): the fraction of
the area that counts whose cells are heard from some node. The signal map is the best RSSI per cell.

One parameter pack describes the radio for the kernels (:class:`Hearing`), so the link table, coverage and the
signal map apply the very same rule.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numba import njit

from amronet.engine.propagation import MIN_DISTANCE_M, LinkBudget
from amronet.engine.shadowing import ShadowingField, _cell_value, _lookup, link_shadowing
from amronet.engine.walls import count_walls, wall_grid
from amronet.world.occupancy import OccupancyMap

__all__ = ["BLOCK", "Hearing", "best_margin_grid", "cell_field", "heard_box", "heard_cells", "link_margin"]


def _frozen(a: np.ndarray) -> np.ndarray:
    a.flags.writeable = False
    return a


# The stand-ins of a radio without walls or shadowing have the dtypes and the read-only flag of the real grids
# (:func:`~amronet.engine.walls.wall_grid`, :class:`~amronet.engine.shadowing.ShadowingField`): numba compiles one
# version of each kernel per argument type, so every radio model then shares one compiled kernel.
_NO_WALLS = _frozen(np.zeros((0, 0), np.uint8))
_NO_JUMP = _frozen(np.zeros((0, 0), np.float32))
_NO_SHADOW = _frozen(np.zeros((1, 1)))


@dataclass(frozen=True)
class Hearing:
    """A radio's rule, as plain numbers and arrays for the compiled kernels.

    Built by :meth:`from_budget`; ``walls`` is an empty grid when the model ignores walls and ``shadow`` a 1x1
    zero grid when it has no shadowing.
    """

    r_c: float
    n10: float
    wall_db: float
    walls: np.ndarray
    jump: np.ndarray
    ox: float
    oy: float
    res: float
    shadow: np.ndarray
    sx0: float
    sy0: float
    sh: float
    corr: float
    clip: float
    reach: float

    @classmethod
    def from_budget(cls, budget: LinkBudget, omap: OccupancyMap | None, field: ShadowingField | None) -> Hearing:
        """The rule of ``budget``; walls come from ``omap`` when ``budget.wall_db > 0``."""
        use_walls = budget.wall_db > 0 and omap is not None
        walls, jump = wall_grid(omap) if use_walls else (_NO_WALLS, _NO_JUMP)
        ox, oy = (float(omap.origin[0]), float(omap.origin[1])) if omap is not None else (0.0, 0.0)
        res = float(omap.resolution) if omap is not None else 1.0
        if field is None:
            shadow, sx0, sy0, sh = _NO_SHADOW, 0.0, 0.0, 1.0
        else:
            shadow, sx0, sy0, sh = field.grid, field.x0, field.y0, field.h
        wall_db = float(budget.wall_db) if use_walls else 0.0
        return cls(r_c=budget.r_c, n10=10.0 * budget.exponent, wall_db=wall_db,
                   walls=walls, jump=jump, ox=ox, oy=oy, res=res, shadow=shadow, sx0=sx0, sy0=sy0, sh=sh,
                   corr=budget.shadowing_corr_m,
                   clip=0.0 if field is None else budget.shadowing_clip * budget.shadowing_db,
                   reach=budget.reach)

    def args(self) -> tuple:
        """The positional arguments of the kernels, in order."""
        return (self.r_c, self.n10, self.wall_db, self.walls, self.jump, self.ox, self.oy, self.res, self.shadow,
                self.sx0, self.sy0, self.sh, self.corr, self.clip)


@njit(cache=True, inline="always")
def link_margin(xa, ya, xb, yb, d, sa, sb, floor_db, r_c, n10, wall_db, walls, jump, ox, oy, res, shadow, sx0, sy0, sh,
                corr, clip):  # pragma: no cover - numba
    """Margin (dB over the threshold) of the link ``a -> b`` of length ``d``; field values ``sa``, ``sb``.

    Walls are counted only while the margin can stay above ``floor_db``: a result below ``floor_db`` is a bound,
    not the exact margin (``floor_db = 0`` decides usability; the signal map passes its display floor).
    """
    m = n10 * math.log10(r_c / max(d, MIN_DISTANCE_M))
    if clip > 0.0:
        m += link_shadowing(sa, sb, d, corr, clip)
    if wall_db > 0.0 and m >= floor_db:
        limit = int(math.floor((m - floor_db) / wall_db)) + 1
        m -= wall_db * count_walls(walls, jump, ox, oy, res, xa, ya, xb, yb, limit)
    return m


BLOCK = 8
"""Cells per side of the blocks that the coverage and signal kernels cull as a whole (see :func:`cell_field`)."""


def cell_field(shape: tuple[int, int], gox: float, goy: float, gres: float, shadow: np.ndarray, sx0: float,
               sy0: float, sh: float, clip: float) -> tuple[np.ndarray, np.ndarray]:
    """The shadowing field at every cell centre of a grid, and its maximum over blocks of :data:`BLOCK` cells.

    The kernels bound a block's best margin by its nearest point and its largest field value, and skip the block
    when even that bound is below what they look for.
    """
    rows, cols = shape
    if clip == 0.0:
        return np.zeros((1, 1)), np.zeros((1, 1))
    cy = goy + (np.arange(rows) + 0.5) * gres
    cx = gox + (np.arange(cols) + 0.5) * gres
    xx, yy = np.meshgrid(cx, cy)
    values = _lookup(shadow, sx0, sy0, sh, xx.ravel(), yy.ravel()).reshape(rows, cols)
    nb_r, nb_c = -(-rows // BLOCK), -(-cols // BLOCK)
    padded = np.full((nb_r * BLOCK, nb_c * BLOCK), -np.inf)
    padded[:rows, :cols] = values
    bmax = padded.reshape(nb_r, BLOCK, nb_c, BLOCK).max(axis=(1, 3))
    return values, bmax


@njit(cache=True, inline="always")
def _shadow_bound(v, clip):  # pragma: no cover - numba
    """Largest link shadowing of two field values summing to ``v``: ``sqrt(2 (1 + rho))`` is in [sqrt 2, 2]."""
    b = v / math.sqrt(2.0) if v >= 0.0 else v / 2.0
    return min(max(b, -clip), clip)


@njit(cache=True, inline="always")
def _block_gap(x, y, gox, goy, gres, bi, bj, rows, cols):  # pragma: no cover - numba
    """Distance from ``(x, y)`` to the nearest cell centre of block ``(bi, bj)`` (a lower bound)."""
    i0 = bi * BLOCK
    j0 = bj * BLOCK
    i1 = min(i0 + BLOCK - 1, rows - 1)
    j1 = min(j0 + BLOCK - 1, cols - 1)
    ylo = goy + (i0 + 0.5) * gres
    yhi = goy + (i1 + 0.5) * gres
    xlo = gox + (j0 + 0.5) * gres
    xhi = gox + (j1 + 0.5) * gres
    dx = xlo - x if x < xlo else (x - xhi if x > xhi else 0.0)
    dy = ylo - y if y < ylo else (y - yhi if y > yhi else 0.0)
    return math.sqrt(dx * dx + dy * dy)


@njit(cache=True, inline="always")
def _node_box(x, y, reach, gox, goy, gres, rows, cols):  # pragma: no cover - numba
    """The cells ``i0..i1, j0..j1`` within ``reach`` of ``(x, y)`` on the grid (empty when ``i0 > i1``)."""
    i0 = max(int(math.floor((y - reach - goy) / gres)), 0)
    i1 = min(int(math.floor((y + reach - goy) / gres)), rows - 1)
    j0 = max(int(math.floor((x - reach - gox) / gres)), 0)
    j1 = min(int(math.floor((x + reach - gox) / gres)), cols - 1)
    return i0, i1, j0, j1


@njit(cache=True)
def _mark_node(x, y, mask, gox, goy, gres, reach, out, oi, oj, cell_s, block_s, r_c, n10, wall_db, walls, jump, ox,
               oy, res, shadow, sx0, sy0, sh, corr, clip):  # pragma: no cover - numba
    """Mark ``out[i - oi, j - oj]`` for the ``mask`` cells ``(i, j)`` heard from the node at ``(x, y)``.

    Cells already marked are skipped. Returns how many were newly marked.
    """
    rows, cols = mask.shape
    total = 0
    sa = _cell_value(shadow, sx0, sy0, sh, x, y) if clip > 0.0 else 0.0
    i0, i1, j0, j1 = _node_box(x, y, reach, gox, goy, gres, rows, cols)
    if i0 > i1 or j0 > j1:
        return 0
    for bi in range(i0 // BLOCK, i1 // BLOCK + 1):
        for bj in range(j0 // BLOCK, j1 // BLOCK + 1):
            gap = _block_gap(x, y, gox, goy, gres, bi, bj, rows, cols)
            if gap > reach:
                continue
            up = n10 * math.log10(r_c / max(gap, MIN_DISTANCE_M))
            if clip > 0.0:
                up += _shadow_bound(sa + block_s[bi, bj], clip)
            if up < 0.0:
                continue
            for i in range(max(bi * BLOCK, i0), min(bi * BLOCK + BLOCK, i1 + 1)):
                cy = goy + (i + 0.5) * gres
                for j in range(max(bj * BLOCK, j0), min(bj * BLOCK + BLOCK, j1 + 1)):
                    if not mask[i, j] or out[i - oi, j - oj]:
                        continue
                    cx = gox + (j + 0.5) * gres
                    d = math.sqrt((cx - x) * (cx - x) + (cy - y) * (cy - y))
                    if d > reach:
                        continue
                    sb = cell_s[i, j] if clip > 0.0 else 0.0
                    m = link_margin(x, y, cx, cy, d, sa, sb, 0.0, r_c, n10, wall_db, walls, jump, ox, oy, res,
                                    shadow, sx0, sy0, sh, corr, clip)
                    if m >= 0.0:
                        out[i - oi, j - oj] = True
                        total += 1
    return total


@njit(cache=True)
def heard_cells(xy, mask, gox, goy, gres, reach, covered, cell_s, block_s, r_c, n10, wall_db, walls, jump, ox, oy, res,
                shadow, sx0, sy0, sh, corr, clip):  # pragma: no cover - numba
    """Mark in ``covered`` the ``mask`` cells heard from a node of ``xy``; return how many were newly marked.

    The grid has origin ``gox, goy`` and cell ``gres``; cells already marked are skipped; ``cell_s`` and ``block_s``
    are :func:`cell_field` of the grid.
    """
    total = 0
    for k in range(xy.shape[0]):
        total += _mark_node(xy[k, 0], xy[k, 1], mask, gox, goy, gres, reach, covered, np.intp(0), np.intp(0),
                            cell_s, block_s, r_c, n10, wall_db, walls, jump, ox, oy, res, shadow, sx0, sy0, sh, corr,
                            clip)
    return total


@njit(cache=True)
def heard_box(x, y, mask, gox, goy, gres, reach, cell_s, block_s, r_c, n10, wall_db, walls, jump, ox, oy, res,
              shadow, sx0, sy0, sh, corr, clip):  # pragma: no cover - numba
    """The cells heard from one node, as ``(i0, j0, piece)``: ``piece[i - i0, j - j0]`` for the cells of its box.

    The same decisions as :func:`heard_cells` (cell by cell they depend on the node and the cell alone), so a
    coverage assembled from boxes is the one :func:`heard_cells` marks.
    """
    i0, i1, j0, j1 = _node_box(x, y, reach, gox, goy, gres, mask.shape[0], mask.shape[1])
    piece = np.zeros((max(i1 - i0 + 1, 0), max(j1 - j0 + 1, 0)), np.bool_)
    if i0 <= i1 and j0 <= j1:
        _mark_node(x, y, mask, gox, goy, gres, reach, piece, i0, j0, cell_s, block_s, r_c, n10, wall_db, walls, jump,
                   ox, oy, res, shadow, sx0, sy0, sh, corr, clip)
    return i0, j0, piece


@njit(cache=True)
def best_margin_grid(xy, gox, goy, gres, out, floor_db, cell_s, block_s, r_c, n10, wall_db, walls, jump, ox, oy, res,
                     shadow, sx0, sy0, sh, corr, clip):  # pragma: no cover - numba
    """``out[i, j]``: the best margin over the nodes ``xy`` at the centre of cell ``(i, j)``.

    Only margins at or above ``floor_db`` are written (cells below it keep their value; fill ``out`` with ``-inf``
    first).
    """
    rows, cols = out.shape
    reach = r_c * 10.0 ** ((clip - floor_db) / n10)
    for k in range(xy.shape[0]):
        x = xy[k, 0]
        y = xy[k, 1]
        sa = _cell_value(shadow, sx0, sy0, sh, x, y) if clip > 0.0 else 0.0
        i0 = max(int(math.floor((y - reach - goy) / gres)), 0)
        i1 = min(int(math.floor((y + reach - goy) / gres)), rows - 1)
        j0 = max(int(math.floor((x - reach - gox) / gres)), 0)
        j1 = min(int(math.floor((x + reach - gox) / gres)), cols - 1)
        if i0 > i1 or j0 > j1:
            continue
        for bi in range(i0 // BLOCK, i1 // BLOCK + 1):
            for bj in range(j0 // BLOCK, j1 // BLOCK + 1):
                gap = _block_gap(x, y, gox, goy, gres, bi, bj, rows, cols)
                up = n10 * math.log10(r_c / max(gap, MIN_DISTANCE_M))
                if clip > 0.0:
                    up += _shadow_bound(sa + block_s[bi, bj], clip)
                if up < floor_db:
                    continue
                for i in range(max(bi * BLOCK, i0), min(bi * BLOCK + BLOCK, i1 + 1)):
                    cy = goy + (i + 0.5) * gres
                    for j in range(max(bj * BLOCK, j0), min(bj * BLOCK + BLOCK, j1 + 1)):
                        cx = gox + (j + 0.5) * gres
                        d = math.sqrt((cx - x) * (cx - x) + (cy - y) * (cy - y))
                        if d > reach:
                            continue
                        sb = cell_s[i, j] if clip > 0.0 else 0.0
                        upper = n10 * math.log10(r_c / max(d, MIN_DISTANCE_M))
                        if clip > 0.0:
                            upper += _shadow_bound(sa + sb, clip)
                        if upper <= out[i, j] or upper < floor_db:
                            continue
                        m = link_margin(x, y, cx, cy, d, sa, sb, max(floor_db, out[i, j]), r_c, n10, wall_db, walls,
                                        jump, ox, oy, res, shadow, sx0, sy0, sh, corr, clip)
                        if m >= floor_db and m > out[i, j]:
                            out[i, j] = m
