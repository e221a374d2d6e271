"""Wall shadows and clear lines that let coverage skip wall walks: each agrees with the walk and finds most cells."""

from __future__ import annotations

import functools
import math

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from amronet.engine.occlusion import BINS, EPS, NEAR, SHRINK, _span, behind, clear, dark, look, shade
from amronet.engine.wall_bits import wall_bits
from amronet.engine.walls import count_walls_many, wall_grid
from amronet.world.builtin import resolve_map

REACH = 12.0


@functools.cache
def _office():
    omap = resolve_map("office-32x32")
    return omap, wall_grid(omap), wall_bits(omap)


def _shade(omap, bits, x: float, y: float) -> tuple[np.ndarray, np.ndarray]:
    out, lit = np.empty(BINS), np.empty(BINS)
    shade(x, y, REACH, bits, omap.shape[1], float(omap.origin[0]), float(omap.origin[1]), float(omap.resolution), out,
          lit)
    return out, lit


def _shadows(omap, bits, x: float, y: float) -> np.ndarray:
    return _shade(omap, bits, x, y)[0]


def _node(omap, grid, rng, where: str) -> np.ndarray:
    """A point in a free cell, on a cell's face or corner, or in a wall cell."""
    res = float(omap.resolution)
    rows, cols = np.nonzero(grid[0] == (1 if where == "wall" else 0))
    k = rng.integers(len(rows))
    node = omap.cell_centres(rows[k:k + 1], cols[k:k + 1])[0]
    if where == "face":  # on a cell border (a wall's face when a wall cell is beside)
        node = node + np.array([0.5 * res * rng.choice([-1.0, 1.0]), 0.0])
    elif where == "corner":
        node = node + 0.5 * res * rng.choice([-1.0, 1.0], 2)
    return node


def _walls(omap, grid, node, ends) -> np.ndarray:
    walls, jump = grid
    return count_walls_many(walls, jump, float(omap.origin[0]), float(omap.origin[1]), float(omap.resolution),
                            np.tile(node, (len(ends), 1)), ends, np.full(len(ends), 10**6, np.int64))


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(seed=st.integers(0, 2**32 - 1), where=st.sampled_from(["free", "face", "corner", "wall"]))
def test_a_point_in_a_shadow_is_behind_a_wall_the_walk_counts(seed, where):
    omap, grid, bits = _office()
    rng = np.random.default_rng(seed)
    res = float(omap.resolution)
    node = _node(omap, grid, rng, where)
    shadows = _shadows(omap, bits, *node)
    # points anywhere within reach (not only cell centres), some on cell borders
    ends = node + rng.uniform(-REACH, REACH, (4000, 2))
    ends[::4] = np.round(ends[::4] / res) * res
    ends = ends[(ends >= 0.0).all(axis=1) & (ends < 32.0).all(axis=1)]
    d = ends - node
    dd = (d * d).sum(axis=1)
    shaded = np.array([behind(shadows, dx, dy, s) for (dx, dy), s in zip(d, dd, strict=True)])
    assert shaded.any()
    assert (_walls(omap, grid, node, ends[shaded]) >= 1).all()


def test_most_cells_behind_a_wall_are_found_in_its_shadow():
    omap, grid, bits = _office()
    rng = np.random.default_rng(7)
    rows, cols = np.nonzero(grid[0] == 0)
    found = blocked = 0
    for k in rng.choice(len(rows), 6, replace=False):
        node = omap.cell_centres(rows[k:k + 1], cols[k:k + 1])[0]
        shadows = _shadows(omap, bits, *node)
        pick = rng.choice(len(rows), 3000, replace=False)
        ends = omap.cell_centres(rows[pick], cols[pick])
        d = ends - node
        dd = (d * d).sum(axis=1)
        ends, d, dd = ends[dd < (0.9 * REACH) ** 2], d[dd < (0.9 * REACH) ** 2], dd[dd < (0.9 * REACH) ** 2]
        walled = _walls(omap, grid, node, ends) >= 1
        shaded = np.array([behind(shadows, dx, dy, s) for (dx, dy), s in zip(d, dd, strict=True)])
        assert not (shaded & ~walled).any()
        found += int(np.count_nonzero(shaded))
        blocked += int(np.count_nonzero(walled))
    assert found > 0.8 * blocked  # the walks coverage skips


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(seed=st.integers(0, 2**32 - 1), where=st.sampled_from(["free", "face", "corner", "wall"]))
def test_a_point_on_a_clear_line_has_no_wall_the_walk_counts(seed, where):
    omap, grid, bits = _office()
    rng = np.random.default_rng(seed)
    res = float(omap.resolution)
    node = _node(omap, grid, rng, where)
    lit = _shade(omap, bits, *node)[1]
    # points anywhere within reach, many near the node, some on cell borders and along the axes
    ends = node + rng.uniform(-1.0, 1.0, (4000, 2)) * rng.choice([0.5, 3.0, REACH], (4000, 1))
    ends[::4] = np.round(ends[::4] / res) * res
    ends[1::8, 0] = node[0]
    ends[3::8, 1] = node[1]
    ends = ends[(ends >= 0.0).all(axis=1) & (ends < 32.0).all(axis=1)]
    d = ends - node
    dd = (d * d).sum(axis=1)
    keep = (dd > 0.0) & (dd <= REACH**2)
    ends, d, dd = ends[keep], d[keep], dd[keep]
    lit_up = np.array([clear(lit, dx, dy, s) for (dx, dy), s in zip(d, dd, strict=True)])
    if where == "wall":
        assert not lit_up.any()  # a node in a wall cell: no line is known clear
    elif where == "free":  # (a face or corner may touch a wall cell: then none either)
        assert lit_up.any()
    assert (_walls(omap, grid, node, ends[lit_up]) == 0).all()


def test_most_cells_in_sight_are_found_on_clear_lines():
    omap, grid, bits = _office()
    rng = np.random.default_rng(8)
    rows, cols = np.nonzero(grid[0] == 0)
    found = seen = 0
    for k in rng.choice(len(rows), 6, replace=False):
        node = omap.cell_centres(rows[k:k + 1], cols[k:k + 1])[0]
        lit = _shade(omap, bits, *node)[1]
        pick = rng.choice(len(rows), 3000, replace=False)
        ends = omap.cell_centres(rows[pick], cols[pick])
        d = ends - node
        dd = (d * d).sum(axis=1)
        keep = (dd > 0.0) & (dd < REACH**2)
        ends, d, dd = ends[keep], d[keep], dd[keep]
        open_ = _walls(omap, grid, node, ends) == 0
        lit_up = np.array([clear(lit, dx, dy, s) for (dx, dy), s in zip(d, dd, strict=True)])
        assert not (lit_up & ~open_).any()
        found += int(np.count_nonzero(lit_up))
        seen += int(np.count_nonzero(open_))
    assert found > 0.8 * seen  # the walks and box tests coverage skips


@pytest.mark.parametrize("node", [(6.3695, -0.0315), (6.3695, -1e-9)])
def test_a_node_outside_the_map_has_no_clear_line(node):
    """The walk counts everything outside the map as wall: a line from a node there is never known clear."""
    omap = resolve_map("hospital_section")
    grid, bits = wall_grid(omap), wall_bits(omap)
    out, lit = np.empty(BINS), np.empty(BINS)
    shade(*node, 3.0, bits, omap.shape[1], float(omap.origin[0]), float(omap.origin[1]), float(omap.resolution),
          out, lit)
    rows, cols = np.nonzero(grid[0][:60, :400] == 0)  # free cells near the node (row 0 is free there)
    ends = omap.cell_centres(rows, cols)
    d = ends - np.array(node)
    dd = (d * d).sum(axis=1)
    lit_up = np.array([clear(lit, dx, dy, s) for (dx, dy), s in zip(d, dd, strict=True)])
    assert not lit_up.any()
    assert (_walls(omap, grid, np.array(node), ends) > 0).all()  # the walk: each line leaves the map first


def _gap(lo: float, hi: float) -> float:
    return lo if lo > 0.0 else (-hi if hi < 0.0 else 0.0)


def _cell_by_cell(bits, cols: int, x: float, y: float, reach: float, ox: float, oy: float, res: float):
    """:func:`shade` drawn wall cell by wall cell over every wall cell within reach, none passed over: its numbers."""
    out, lit = np.full(BINS, np.inf), np.full(BINS, np.inf)
    rows, scale, s = bits.shape[1], BINS / 4.0, SHRINK * res
    span = _span.py_func
    if not (0 <= math.floor((y - oy) / res) < rows and 0 <= math.floor((x - ox) / res) < cols):
        lit[:], lit[0] = 0.0, -1.0
    r0, r1 = max(math.floor((y - reach - oy) / res), 0), min(math.floor((y + reach - oy) / res), rows - 1)
    c0, c1 = max(math.floor((x - reach - ox) / res), 0), min(math.floor((x + reach - ox) / res), cols - 1)
    walls = np.unpackbits(bits[0].view(np.uint8), axis=1, bitorder="little")[:, :cols]
    far2 = reach * reach
    for r, c in zip(*np.nonzero(walls[r0:r1 + 1, c0:c1 + 1]), strict=True):
        r, c = int(r) + r0, int(c) + c0
        dy0, dy1 = oy + r * res + s - y, oy + (r + 1) * res - s - y
        dx0, dx1 = ox + c * res + s - x, ox + (c + 1) * res - s - x
        gx, gy = _gap(dx0, dx1), _gap(dy0, dy1)
        ex0, ex1, ey0, ey1 = dx0 - 2.0 * s, dx1 + 2.0 * s, dy0 - 2.0 * s, dy1 + 2.0 * s  # the cell grown
        hx, hy = _gap(ex0, ex1), _gap(ey0, ey1)
        if lit[0] >= 0.0 and hx == 0.0 and hy == 0.0:
            lit[:], lit[0] = 0.0, -1.0
        elif lit[0] >= 0.0 and hx * hx + hy * hy <= far2:
            lo, hi = span(ex0, ex1, ey0, ey1)
            for b in range(math.floor((lo - EPS) * scale), math.floor((hi + EPS) * scale) + 1):
                lit[b % BINS] = min(lit[b % BINS], hx * hx + hy * hy)
        gap2 = gx * gx + gy * gy
        if (NEAR * res) * (NEAR * res) <= gap2 <= far2:
            f2 = max(dx0 * dx0, dx1 * dx1) + max(dy0 * dy0, dy1 * dy1)
            lo, hi = span(dx0, dx1, dy0, dy1)
            for b in range(math.ceil((lo + EPS) * scale), math.floor((hi - EPS) * scale)):
                out[b % BINS] = min(out[b % BINS], f2)
    return out, lit


@settings(max_examples=12, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(seed=st.integers(0, 2**32 - 1), where=st.sampled_from(["free", "face", "corner", "wall", "outside"]),
       reach=st.sampled_from([0.3, 2.0, 5.0]))
def test_shade_passing_over_blocks_gives_the_numbers_of_every_wall_cell_drawn(seed, where, reach):
    omap, grid, bits = _office()
    rng = np.random.default_rng(seed)
    node = np.array([-0.3, 31.0 * rng.uniform()]) if where == "outside" else _node(omap, grid, rng, where)
    ox, oy, res = float(omap.origin[0]), float(omap.origin[1]), float(omap.resolution)
    out, lit = np.empty(BINS), np.empty(BINS)
    shade(*node, reach, bits, omap.shape[1], ox, oy, res, out, lit)
    want_out, want_lit = _cell_by_cell(bits, omap.shape[1], *node, reach, ox, oy, res)
    np.testing.assert_array_equal(out, want_out)
    np.testing.assert_array_equal(lit, want_lit)


def test_shade_draws_few_of_the_wall_cells_behind_the_nearest_walls():
    omap, grid, bits = _office()
    ox, oy, res = float(omap.origin[0]), float(omap.origin[1]), float(omap.resolution)
    rng = np.random.default_rng(5)
    drawn = walls = 0
    for _ in range(4):
        node = _node(omap, grid, rng, "free")
        drawn += shade(*node, REACH, bits, omap.shape[1], ox, oy, res, np.empty(BINS), np.empty(BINS))
        i0, j0 = max(math.floor((node[1] - REACH - oy) / res), 0), max(math.floor((node[0] - REACH - ox) / res), 0)
        i1, j1 = math.floor((node[1] + REACH - oy) / res), math.floor((node[0] + REACH - ox) / res)
        walls += int(np.count_nonzero(grid[0][i0:i1 + 1, j0:j1 + 1] == 1))  # the wall cells in its box
    assert 0 < drawn < walls // 2


@settings(max_examples=20, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(seed=st.integers(0, 2**32 - 1), where=st.sampled_from(["free", "face", "corner", "wall"]))
def test_a_dark_block_has_every_cell_centre_in_a_shadow(seed, where):
    """Where ``dark`` says so of a block of 8 x 8 cell centres, ``look`` finds each of them in a shadow."""
    omap, grid, bits = _office()
    rng = np.random.default_rng(seed)
    res, ox, oy = float(omap.resolution), float(omap.origin[0]), float(omap.origin[1])
    node = _node(omap, grid, rng, where)
    shadows, lit = _shade(omap, bits, *node)
    near2 = (NEAR * res) ** 2
    found = 0
    for i0, j0 in rng.integers(0, omap.shape[0] - 8, (300, 2)):
        cx = ox + (np.arange(j0, j0 + 8) + 0.5) * res - node[0]
        cy = oy + (np.arange(i0, i0 + 8) + 0.5) * res - node[1]
        if not dark(lit, shadows, cx[0], cx[-1], cy[0], cy[-1], near2):
            continue
        found += 1
        assert all(look(lit, shadows, dx, dy, dx * dx + dy * dy, near2) == -1 for dx in cx for dy in cy)
    assert found > 0 or where == "wall"
