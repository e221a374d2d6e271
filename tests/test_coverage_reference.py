"""Coverage under the path-loss radios against the law written out, cell by cell and node by node, on real maps.

A free cell is covered when some node's link budget to the cell's centre is ``>= 0``: distance, shadowing and the
walls the straight line crosses (:func:`~amronet.engine.walls.count_walls`, the byte walk, counted in full). The
reference below decides every cell of the map for every node that way; the radio's coverage
(:class:`~amronet.engine.coverage_heard.HeardCells`, its kernels and its running unions, with two sets of nodes
asked about in turn as a run does) must mark exactly the same cells.
"""

from __future__ import annotations

import functools
import math
from pathlib import Path

import numpy as np
import pytest

from amronet.engine.coverage import CoverageArea
from amronet.engine.coverage_heard import HeardCells
from amronet.engine.hearing import node_reach, path_loss_bound
from amronet.engine.propagation import MIN_DISTANCE_M, LinkBudget
from amronet.engine.radio import RadioMedium, make_medium
from amronet.engine.walls import count_walls_many, wall_grid
from amronet.world.builtin import resolve_map
from amronet.world.loading import load_map_yaml
from amronet.world.occupancy import OccupancyMap

DEPOT = Path("/work/shared/maps/depot.yaml")
MAPS = ["hospital_section", "office-32x32", "autolab",
        pytest.param("depot", marks=pytest.mark.skipif(not DEPOT.exists(), reason="no shared depot map"))]


@functools.cache
def _map(name: str) -> OccupancyMap:
    return load_map_yaml(DEPOT) if name == "depot" else resolve_map(name)


def _nodes(omap: OccupancyMap, rng: np.random.Generator, n: int) -> np.ndarray:
    """``n`` points: free cell centres next to a wall cell, points on such a wall's face, and free cells anywhere."""
    walls, _ = wall_grid(omap)
    free = walls == 0
    near = np.zeros_like(free)
    for dr, dc in ((1, 0), (-1, 0), (0, 1), (0, -1)):  # free cells with a wall cell beside them
        shifted = np.zeros_like(free)
        src = walls[max(dr, 0):walls.shape[0] + min(dr, 0), max(dc, 0):walls.shape[1] + min(dc, 0)] != 0
        shifted[max(-dr, 0):walls.shape[0] + min(-dr, 0), max(-dc, 0):walls.shape[1] + min(-dc, 0)] = src
        near |= free & shifted
    rows, cols = np.nonzero(near)
    pick = rng.choice(len(rows), n, replace=False)
    beside = omap.cell_centres(rows[pick], cols[pick])
    face = beside.copy()
    face[: n // 2] += 0.5 * omap.resolution * rng.choice([-1.0, 1.0], (n // 2, 2)) * np.array([1.0, 0.0])
    frows, fcols = np.nonzero(free)
    anywhere = omap.cell_centres(*(a[rng.choice(len(frows), n, replace=False)] for a in (frows, fcols)))
    return np.vstack([beside, face, anywhere])


_DONE: dict[tuple, np.ndarray] = {}
"""One node's cells heard, per medium, mask and position: each is decided once per test."""


def _reference(medium: RadioMedium, omap: OccupancyMap, mask: np.ndarray, xy: np.ndarray) -> np.ndarray:
    """Every cell of ``mask`` decided for every node of ``xy`` by the law written out (see the module doc)."""
    h = medium.hearing
    walls, jump = wall_grid(omap)
    res, (ox, oy) = float(omap.resolution), omap.origin
    rows, cols = np.nonzero(mask)
    cx, cy = ox + (cols + 0.5) * res, oy + (rows + 0.5) * res
    values, fx, fy, fh = h.field

    def field(x: np.ndarray, y: np.ndarray) -> np.ndarray:
        i = np.clip(np.floor((y - fy) / fh).astype(int), 0, values.shape[0] - 1)
        j = np.clip(np.floor((x - fx) / fh).astype(int), 0, values.shape[1] - 1)
        return values[i, j]

    sb = field(cx, cy)
    heard = np.zeros(len(rows), dtype=bool)
    for x, y in xy:
        key = (id(medium), id(mask), x, y)
        if key in _DONE:
            heard |= _DONE[key]
            continue
        d = np.sqrt((cx - x) * (cx - x) + (cy - y) * (cy - y))
        m = np.full(len(d), -np.inf)
        within = np.flatnonzero(d <= 1.01 * h.r_c * 10.0 ** (h.clip / h.n10))  # beyond: below 0 even at most shadowing
        m[within] = [h.n10 * math.log10(h.r_c / max(v, MIN_DISTANCE_M)) for v in d[within]]
        if h.clip > 0.0:
            sa = field(np.array([x]), np.array([y]))[0]
            m += np.clip((sa + sb) / np.sqrt(2.0 * (1.0 + np.exp(-d / h.corr))), -h.clip, h.clip)
        if h.wall_db > 0.0:
            ask = np.flatnonzero(m >= 0.0)
            ends = np.column_stack([cx[ask], cy[ask]])
            count = count_walls_many(walls, jump, ox, oy, res, np.tile([x, y], (len(ask), 1)), ends,
                                     np.full(len(ask), 10**6, np.int64))
            m[ask] -= h.wall_db * count
        _DONE[key] = m >= 0.0
        heard |= _DONE[key]
    out = np.zeros(mask.shape, dtype=bool)
    out[rows, cols] = heard
    return out


@pytest.mark.parametrize("name", MAPS)
@pytest.mark.parametrize(("model", "shadowing_db"), [("multi-wall", 0.0), ("multi-wall", 4.0),
                                                      ("log-distance", 4.0)])
def test_coverage_is_the_law_cell_by_cell_on_real_maps(name, model, shadowing_db):
    omap = _map(name)
    budget = LinkBudget(r_c=3.0, exponent=2.0, wall_db=6.9 if model == "multi-wall" else 0.0,
                        shadowing_db=shadowing_db)
    medium = make_medium(model, budget, omap, rng=np.random.default_rng(11))
    rng = np.random.default_rng(sum(map(ord, name)))
    area = CoverageArea(omap, omap.free)
    every = _nodes(omap, rng, 4)
    linked = every[::2]  # the connected part, asked about between two calls of every node, as a run does
    heard = HeardCells(medium.hearing, medium.kernels)
    moved = every.copy()
    moved[-1] += 0.3 * omap.resolution
    for xy in (every, linked, moved, linked, every):
        got = heard.covered(area, xy, medium.reach)
        want = _reference(medium, omap, area.mask, xy)
        assert np.array_equal(got, want), f"{int(np.count_nonzero(got != want))} cells differ"
    _DONE.clear()


@pytest.mark.parametrize("s", [-30.0, -4.0, 0.0, 6.0, 50.0])
def test_a_node_reach_is_where_its_margin_bound_falls_below_zero(s):
    budget = LinkBudget(r_c=3.0, exponent=2.0, wall_db=6.9, shadowing_db=4.0)
    medium = make_medium("multi-wall", budget, _map("office-32x32"), rng=np.random.default_rng(11))
    h, full = medium.hearing, float(medium.reach)
    reach = node_reach(s, full, h)
    if path_loss_bound(full, s, h) >= 0.0:  # the most shadowing: the medium's own reach
        assert reach == full
    else:  # no link that long or longer is heard, and one a little shorter may be
        assert reach < full
        assert path_loss_bound(reach, s, h) < 0.0 <= path_loss_bound(reach * (1.0 - 1e-6), s, h)
