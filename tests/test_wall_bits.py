"""The radio's wall walk on bit grids (:mod:`amronet.engine.wall_bits`): the same answers as the byte walk.

:func:`count_walls_bits` must count exactly what :func:`amronet.engine.walls.count_walls` counts (it takes the same
steps and leaps, reads bits instead of bytes and stops once the cells left hold no wall), and
:func:`box_clear_bits` must answer what :func:`~amronet.engine.walls.box_clear` answers. Checked on random grids
with ends on and next to cell borders, and on every map in the repository; and the path-loss law's link kernel
against the generic one, shadowing and reuse included.
"""

from __future__ import annotations

import glob

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from numba import njit

from amronet.engine.links import NO_PREVIOUS, candidate_margins, open_pair, open_radius, path_loss_candidate_margins
from amronet.engine.neighbours import neighbour_csr
from amronet.engine.propagation import LinkBudget
from amronet.engine.radio import make_medium
from amronet.engine.wall_bits import ROW_LEVELS, box_clear_bits, count_walls_bits, count_walls_lines, wall_bits
from amronet.engine.walls import LEAP_CELLS, box_clear, count_walls, count_walls_many, wall_grid, wall_sums
from amronet.world.builtin import BUILTIN_MAPS, resolve_map
from amronet.world.occupancy import OccupancyMap
from test_wall_boxes import BIG, grids_and_segments, scattered


@njit(cache=True)
def _bits_many(bits, walls, jump, ox, oy, res, a, b, limit):  # pragma: no cover - numba
    out = np.empty(a.shape[0], np.int64)
    for k in range(a.shape[0]):
        out[k] = count_walls_bits(bits, walls, jump, ox, oy, res, a[k, 0], a[k, 1], b[k, 0], b[k, 1], limit[k])
    return out


@njit(cache=True)
def _boxes_many(bits, cols, ox, oy, res, a, b):  # pragma: no cover - numba
    out = np.empty(a.shape[0], np.bool_)
    for k in range(a.shape[0]):
        out[k] = box_clear_bits(bits, cols, ox, oy, res, a[k, 0], a[k, 1], b[k, 0], b[k, 1])
    return out


@njit(cache=True)
def _lines_many(bits, cols, ox, oy, res, a, b, limit):  # pragma: no cover - numba
    out = np.empty(a.shape[0], np.int64)
    for k in range(a.shape[0]):
        out[k] = count_walls_lines(bits, cols, ox, oy, res, a[k, 0], a[k, 1], b[k, 0], b[k, 1], limit[k])
    return out


@njit(cache=True)
def _sums_many(sums, ox, oy, res, a, b):  # pragma: no cover - numba
    out = np.empty(a.shape[0], np.bool_)
    for k in range(a.shape[0]):
        out[k] = box_clear(sums, ox, oy, res, a[k, 0], a[k, 1], b[k, 0], b[k, 1])
    return out


def test_the_bit_grids_are_the_wall_cells_and_the_leap_cells():
    rng = np.random.default_rng(3)
    cells = np.where(rng.random((70, 150)) < 0.02, 100, 0).astype(np.int8)
    cells[:, 140:] = -1  # unknown: walls too
    omap = OccupancyMap("hand", 0.05, (1.0, -2.0), cells)
    walls, jump = wall_grid(omap)
    bits = wall_bits(omap)
    assert bits.shape == (5 + ROW_LEVELS, 70, 3) and bits.dtype == np.uint64 and not bits.flags.writeable
    assert wall_bits(omap) is bits  # cached with the map
    unpacked = ((bits[:2, :, :, None] >> np.arange(64, dtype=np.uint64)) & np.uint64(1)).reshape(2, 70, 192) == 1
    np.testing.assert_array_equal(unpacked[0, :, :150], walls != 0)
    leap = jump.astype(np.float64) > LEAP_CELLS * 0.05
    assert leap.any() and not leap.all()
    np.testing.assert_array_equal(unpacked[1, :, :150], leap)
    assert not unpacked[:, :, 150:].any()  # the padding is no wall and no leap
    # the wall cells transposed: column c in row c % 70 of grid 2 + c // 70, rows in its first two words
    flip = bits[2:5, :, :2].reshape(210, 2)[:150]
    columns = ((flip[:, :, None] >> np.arange(64, dtype=np.uint64)) & np.uint64(1)).reshape(150, 128) == 1
    np.testing.assert_array_equal(columns[:, :70], (walls != 0).T)
    assert not columns[:, 70:].any()
    for k in range(1, ROW_LEVELS + 1):  # then the wall words OR'ed over 2**k rows from each row on
        expect = np.array([np.bitwise_or.reduce(bits[0, r:r + 2**k], axis=0) for r in range(70)])
        np.testing.assert_array_equal(bits[4 + k], expect)


@settings(max_examples=500, deadline=None)
@given(grids_and_segments(), st.integers(0, 3))
def test_the_bit_walk_counts_what_the_byte_walk_counts(case, limit):
    omap, a, b = case
    walls, jump = wall_grid(omap)
    bits = wall_bits(omap)
    ox, oy, res = float(omap.origin[0]), float(omap.origin[1]), float(omap.resolution)
    for lim in (limit, BIG):
        assert count_walls_bits(bits, walls, jump, ox, oy, res, *a, *b, lim) == count_walls(walls, jump, ox, oy, res,
                                                                                           *a, *b, lim)
    assert box_clear_bits(bits, walls.shape[1], ox, oy, res, *a, *b) == box_clear(wall_sums(omap), ox, oy, res, *a,
                                                                                   *b)


@pytest.mark.parametrize("name", [*BUILTIN_MAPS, *sorted(glob.glob("/work/shared/maps/*.yaml"))])
def test_the_bit_walk_on_every_map(name):
    """Short and long segments (the radio's links, coverage's reach) and ends on cell corners, with limits."""
    omap = resolve_map(name)
    walls, jump = wall_grid(omap)
    bits = wall_bits(omap)
    ox, oy, res = float(omap.origin[0]), float(omap.origin[1]), float(omap.resolution)
    xmin, xmax, ymin, ymax = omap.extent
    rng = np.random.default_rng(len(name))
    n = 40_000
    a = np.column_stack([rng.uniform(xmin - 0.5, xmax + 0.5, n), rng.uniform(ymin - 0.5, ymax + 0.5, n)])
    b = a + rng.normal(0.0, 1.0, (n, 2)) * rng.choice([0.02, 0.05, 0.3], n)[:, None] * max(xmax - xmin, ymax - ymin)
    b[::17, 1] = a[::17, 1]  # along a row
    b[::19, 0] = a[::19, 0]  # along a column
    a[::23] = np.round((a[::23] - (ox, oy)) / res) * res + (ox, oy)  # on cell corners
    for limit in (np.full(n, BIG), rng.integers(0, 4, n)):
        np.testing.assert_array_equal(_bits_many(bits, walls, jump, ox, oy, res, a, b, limit),
                                      count_walls_many(walls, jump, ox, oy, res, a, b, limit))
    np.testing.assert_array_equal(_boxes_many(bits, walls.shape[1], ox, oy, res, a, b),
                                  _sums_many(wall_sums(omap), ox, oy, res, a, b))


@pytest.mark.parametrize("name", ["hospital_section", "office-32x32"])
def test_the_line_count_is_the_walks_next_to_cell_corners(name):
    """Segments through cell corners and 1e-13 to 1e-3 of a cell beside them, ends on and next to cell borders."""
    omap = resolve_map(name)
    walls, jump = wall_grid(omap)
    bits = wall_bits(omap)
    ox, oy, res = float(omap.origin[0]), float(omap.origin[1]), float(omap.resolution)
    rng = np.random.default_rng(5)
    n = 30_000
    corner = np.column_stack([rng.integers(0, walls.shape[1] + 1, n), rng.integers(0, walls.shape[0] + 1, n)])
    angle = rng.uniform(0.0, 2.0 * np.pi, n)
    along = np.column_stack([np.cos(angle), np.sin(angle)])
    beside = rng.choice([0.0, 1e-13, 1e-10, 1e-7, 1e-6, 2e-6, 1e-5, 1e-3], n)[:, None] * along[:, ::-1] * (-1, 1)
    a = corner - rng.uniform(0.0, 30.0, n)[:, None] * along + beside
    b = corner + rng.uniform(0.0, 30.0, n)[:, None] * along + beside
    a[::5] = np.round(a[::5]) + rng.choice([0.0, 1e-9, -1e-7, 3e-6], (len(a[::5]), 2))  # ends at and by corners
    b[::7] = np.round(b[::7] * 2.0) / 2.0 + rng.choice([0.0, 1e-9, -1e-7, 3e-6], (len(b[::7]), 2))
    a, b = a * res + (ox, oy), b * res + (ox, oy)
    for limit in (np.full(n, BIG), rng.integers(0, 4, n)):
        lines = _lines_many(bits, walls.shape[1], ox, oy, res, a, b, limit)
        decided = lines >= 0
        assert 0.2 < decided.mean() < 0.95  # both the lines and the walk count
        np.testing.assert_array_equal(lines[decided], count_walls_many(walls, jump, ox, oy, res, a, b, limit)[decided])


@pytest.mark.parametrize("shadowing_db", [0.0, 5.0])
@pytest.mark.parametrize("model", ["multi-wall", "log-distance"])
def test_the_path_loss_kernel_gives_the_generic_kernels_numbers(model, shadowing_db):
    """Bit for bit, with and without walls and shadowing, fresh and reusing a previous table."""
    omap = resolve_map("office-32x32")
    budget = LinkBudget(r_c=2.0, exponent=2.0, wall_db=6.9 if model == "multi-wall" else 0.0,
                        shadowing_db=shadowing_db)
    medium = make_medium(model, budget, omap, rng=np.random.default_rng(2))
    xy = scattered(omap, 1500, seed=4)
    xy[::40] = np.round(xy[::40] / omap.resolution) * omap.resolution  # some on cell corners
    plain = medium.hearing.plain()
    indptr, indices, dist = neighbour_csr(xy, medium.reach)
    fresh = path_loss_candidate_margins(xy, indptr, indices, dist, *NO_PREVIOUS, plain)
    np.testing.assert_array_equal(fresh, candidate_margins(xy, indptr, indices, dist, *NO_PREVIOUS, plain))
    moved = xy.copy()
    moved[::7] += 0.05
    indptr2, indices2, dist2 = neighbour_csr(moved, medium.reach)
    reused = path_loss_candidate_margins(moved, indptr2, indices2, dist2, xy, indptr, indices, fresh, plain)
    np.testing.assert_array_equal(reused, candidate_margins(moved, indptr2, indices2, dist2, *NO_PREVIOUS, plain))


@njit(cache=True)
def _open_pairs(jump, ox, oy, res, a, b):  # pragma: no cover - numba
    out = np.empty(a.shape[0], np.bool_)
    for k in range(a.shape[0]):
        d = np.sqrt((b[k, 0] - a[k, 0]) ** 2 + (b[k, 1] - a[k, 1]) ** 2)
        out[k] = open_pair(d, open_radius(a[k, 0], a[k, 1], jump, ox, oy, res),
                           open_radius(b[k, 0], b[k, 1], jump, ox, oy, res))
    return out


@pytest.mark.parametrize("name", ["office-32x32", "hospital_section", "obstacles-6x6"])
def test_a_link_within_its_two_ends_open_radii_crosses_no_wall(name):
    """:func:`open_pair`: shorter than the two ends' open radii together, the walk counts no wall."""
    omap = resolve_map(name)
    walls, jump = wall_grid(omap)
    ox, oy, res = float(omap.origin[0]), float(omap.origin[1]), float(omap.resolution)
    rng = np.random.default_rng(5)
    a = scattered(omap, 20_000, seed=6)
    b = a + rng.normal(0.0, 1.0, a.shape) * rng.choice([0.1, 0.5, 2.0], len(a))[:, None]
    b[::29] = a[::29] + 0.5 * (b[::29] - a[::29]).round()  # some along an axis
    clear = _open_pairs(jump, ox, oy, res, a, b)
    d = np.hypot(*(b - a).T)
    ra = np.array([open_radius(x, y, jump, ox, oy, res) for x, y in a])
    rb = np.array([open_radius(x, y, jump, ox, oy, res) for x, y in b])
    assert clear.sum() > (d < np.maximum(ra, rb)).sum() + 100  # more than one end's radius alone decides
    counts = count_walls_many(walls, jump, ox, oy, res, a[clear], b[clear], np.full(int(clear.sum()), BIG))
    assert not counts.any()


def test_open_pair_leaves_an_end_off_the_map_to_the_other():
    assert open_pair(0.5, -1.0, 0.6) and open_pair(0.5, 0.6, -1.0)
    assert not open_pair(0.5, -1.0, 1.2 - 1.0) and not open_pair(0.0, -1.0, -1.0)
    assert open_pair(0.9, 0.5, 0.5) and not open_pair(1.0, 0.5, 0.5)
