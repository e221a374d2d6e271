"""The radio's shortcut past the wall walk: a link whose rectangle of cells holds no wall crosses none.

:func:`amronet.engine.walls.box_clear` reads the map's summed-area table of wall cells (:func:`wall_sums`); where it
says clear, :func:`~amronet.engine.hearing.walls_crossed` answers 0 without walking. These tests check that answer
against the walk itself (with and without its leaps) on random grids with ends on and next to cell borders, and the
margins of every candidate link on every map in the repository against a brute-force margin that always walks.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from amronet.engine.hearing import walls_crossed
from amronet.engine.links import NO_PREVIOUS, candidate_margins, path_loss_candidate_margins
from amronet.engine.neighbours import neighbour_csr
from amronet.engine.propagation import MIN_DISTANCE_M, LinkBudget
from amronet.engine.radio import make_medium
from amronet.engine.wall_bits import wall_bits
from amronet.engine.walls import box_clear, count_walls, count_walls_many, wall_grid, wall_sums
from amronet.world.builtin import BUILTIN_MAPS, resolve_map
from amronet.world.occupancy import FREE, OCCUPIED, UNKNOWN, OccupancyMap

BIG = 10**6


def test_wall_sums_count_the_wall_cells_of_every_rectangle():
    rng = np.random.default_rng(3)
    cells = rng.choice(np.array([FREE, FREE, OCCUPIED, UNKNOWN], dtype=np.int8), size=(17, 23))
    omap = OccupancyMap("hand", 0.1, (0.0, 0.0), cells)
    walls, _ = wall_grid(omap)
    sums = wall_sums(omap)
    assert sums.shape == (18, 24) and sums.dtype == np.int32 and not sums.flags.writeable
    assert wall_sums(omap) is sums  # cached with the map
    for i in range(18):
        for j in range(24):
            assert sums[i, j] == walls[:i, :j].sum()


@st.composite
def grids_and_segments(draw):
    """A grid with wall blocks and a segment whose ends lie on, a hair off, or well inside cell borders."""
    rows, cols = draw(st.integers(3, 30)), draw(st.integers(3, 30))
    cells = np.zeros((rows, cols), dtype=np.int8)
    for _ in range(draw(st.integers(0, 5))):
        r, c = draw(st.integers(0, rows - 1)), draw(st.integers(0, cols - 1))
        h, w = draw(st.integers(1, 6)), draw(st.integers(1, 6))
        cells[r:r + h, c:c + w] = draw(st.sampled_from([OCCUPIED, UNKNOWN]))
    res = draw(st.sampled_from([0.05, 0.1, 0.125, 0.3]) | st.floats(0.01, 2.0))
    origin = (draw(st.floats(-1e4, 1e4)), draw(st.floats(-1e4, 1e4)))
    omap = OccupancyMap("hand", float(res), origin, cells)
    # a hair: none, the last bits, and just above and below the box's margin
    hair = st.sampled_from([0.0, 1e-15, -1e-15, 1e-12, -1e-12, 3e-9, -3e-9, 1e-6, -1e-6]) | st.floats(-0.5, 0.5)
    ends = []
    for _ in range(2):
        u = draw(st.integers(-1, cols + 1)) + draw(hair)
        v = draw(st.integers(-1, rows + 1)) + draw(hair)
        ends.append((origin[0] + u * res, origin[1] + v * res))
    if draw(st.booleans()):  # along a row or a column now and then (the walk's border rule)
        axis = draw(st.integers(0, 1))
        ends[1] = (ends[0][0], ends[1][1]) if axis == 0 else (ends[1][0], ends[0][1])
    return omap, ends[0], ends[1]


@settings(max_examples=400, deadline=None)
@given(grids_and_segments())
def test_a_clear_box_means_the_walk_crosses_no_wall(case):
    omap, a, b = case
    walls, jump = wall_grid(omap)
    ox, oy, res = float(omap.origin[0]), float(omap.origin[1]), float(omap.resolution)
    if box_clear(wall_sums(omap), ox, oy, res, *a, *b):
        assert count_walls(walls, jump, ox, oy, res, *a, *b, BIG) == 0
        assert count_walls(walls, np.zeros_like(jump), ox, oy, res, *a, *b, BIG) == 0  # without leaps too


@settings(max_examples=100, deadline=None)
@given(arrays(np.int8, (9, 11), elements=st.sampled_from([FREE, FREE, FREE, OCCUPIED])), st.data())
def test_box_clear_is_the_rectangle_query(cells, data):
    """Inside the map and away from borders, clear exactly when the rectangle of cells between the ends has no wall."""
    omap = OccupancyMap("hand", 0.1, (0.0, 0.0), cells)
    walls, _ = wall_grid(omap)
    (r0, r1), (c0, c1) = (sorted(data.draw(st.lists(st.integers(0, n - 1), min_size=2, max_size=2)))
                          for n in walls.shape)
    a = ((c0 + 0.37) * 0.1, (r0 + 0.61) * 0.1)
    b = ((c1 + 0.52) * 0.1, (r1 + 0.29) * 0.1)
    flip = data.draw(st.booleans())
    ends = (*b, *a) if flip else (*a, *b)
    assert box_clear(wall_sums(omap), 0.0, 0.0, 0.1, *ends) == (not walls[r0:r1 + 1, c0:c1 + 1].any())


def test_box_clear_never_says_clear_outside_the_map_or_for_nan():
    omap = OccupancyMap("hand", 0.1, (0.0, 0.0), np.zeros((10, 10), dtype=np.int8))
    sums = wall_sums(omap)
    assert box_clear(sums, 0.0, 0.0, 0.1, 0.05, 0.05, 0.95, 0.95)
    assert not box_clear(sums, 0.0, 0.0, 0.1, 0.05, 0.05, 1.05, 0.95)  # the outside is a wall
    assert not box_clear(sums, 0.0, 0.0, 0.1, -0.05, 0.05, 0.5, 0.5)
    assert not box_clear(sums, 0.0, 0.0, 0.1, math.nan, 0.05, 0.5, 0.5)
    assert not box_clear(sums, 0.0, 0.0, 0.1, 0.0, 0.05, 0.5, 0.5)  # on the map's edge: within the margin


def test_walls_crossed_asks_the_box_first():
    """With a wall grid the walk would count but bit grids saying clear, the answer is the bits': no walk."""
    omap = OccupancyMap("hand", 0.1, (0.0, 0.0), np.zeros((10, 30), dtype=np.int8))
    medium = make_medium("multi-wall", 1.0, omap)
    h = medium.hearing
    blocked = np.zeros((10, 30), np.uint8)
    blocked[:, 10] = 1  # a wall the walk meets, which the summed-area table does not know of
    walled = h._replace(walls=h.walls._replace(blocked=blocked))
    assert walls_crossed(0.52, 0.53, 2.07, 0.48, BIG, walled) == 0
    fenced = walled._replace(wall_bits=wall_bits(OccupancyMap("w", 0.1, (0.0, 0.0),
                                                              np.where(blocked == 1, OCCUPIED, FREE).astype(np.int8))))
    assert walls_crossed(0.52, 0.53, 2.07, 0.48, BIG, fenced) == 1


def brute_margins(xy: np.ndarray, indptr: np.ndarray, indices: np.ndarray, dist: np.ndarray, omap: OccupancyMap,
                  budget: LinkBudget) -> np.ndarray:
    """The multi-wall margin of every candidate (CSR order), every wall count by the walk (no box, no reuse)."""
    walls, jump = wall_grid(omap)
    rows = np.repeat(np.arange(len(xy)), np.diff(indptr))
    lo, hi = np.minimum(rows, indices), np.maximum(rows, indices)  # walked from the lower id, as the medium does
    n10, r_c, wall_db = 10.0 * budget.exponent, budget.r_c, budget.wall_db
    m0 = [n10 * math.log10(r_c / max(float(d), MIN_DISTANCE_M)) for d in dist]
    limit = np.array([int(math.floor(m / wall_db)) + 1 if m >= 0.0 else 0 for m in m0], dtype=np.int64)
    count = count_walls_many(walls, jump, float(omap.origin[0]), float(omap.origin[1]), float(omap.resolution),
                             xy[lo], xy[hi], limit)
    return np.array([m - wall_db * c if m >= 0.0 else m for m, c in zip(m0, count, strict=True)])


def scattered(omap: OccupancyMap, n: int, seed: int) -> np.ndarray:
    """``n`` points in the free cells of ``omap``, anywhere within their cells."""
    rng = np.random.default_rng(seed)
    r, c = np.nonzero(omap.free)
    pick = rng.choice(len(r), size=min(n, len(r)), replace=False)
    return omap.cell_centres(r[pick], c[pick]) + rng.uniform(-0.5, 0.5, (len(pick), 2)) * omap.resolution


@pytest.mark.parametrize("name", [*BUILTIN_MAPS, "/work/shared/maps/hospital_section.yaml", "bench"])
def test_margins_on_real_maps_equal_a_brute_force_walk(name):
    """Every candidate's margin, bit for bit, on every built-in map (and ``amronet bench``'s scaled hospital)."""
    if name.startswith("/") and not __import__("os").path.exists(name):
        pytest.skip("the shared maps are not on this machine")
    omap = resolve_map("hospital_section" if name == "bench" else name)
    r_c = 1.0
    if name == "bench":  # scaled as the radio benchmark scales it: 0.25 m² per robot for 3 000 robots
        area = np.count_nonzero(omap.free) * omap.resolution**2
        omap = dataclasses.replace(omap, resolution=omap.resolution * math.sqrt(3000 * 0.25 / area), _cache={})
    else:
        r_c = max(1.0, 0.05 * min(omap.extent[1] - omap.extent[0], omap.extent[3] - omap.extent[2]))
    budget = LinkBudget(r_c=r_c, exponent=2.0, wall_db=6.9)
    free_area = np.count_nonzero(omap.free) * omap.resolution**2
    xy = scattered(omap, min(1500, int(15 * free_area / (math.pi * r_c**2))), seed=len(name))  # degree ~15
    indptr, indices, dist = neighbour_csr(xy, r_c)
    medium = make_medium("multi-wall", budget, omap)
    fast = candidate_margins(xy, indptr, indices, dist, *NO_PREVIOUS, medium.hearing.plain())
    np.testing.assert_array_equal(fast, brute_margins(xy, indptr, indices, dist, omap, budget))
    law = path_loss_candidate_margins(xy, indptr, indices, dist, *NO_PREVIOUS, medium.hearing.plain())
    np.testing.assert_array_equal(law, fast)  # the path-loss law's own kernel: the same numbers
    ox, oy, res = float(omap.origin[0]), float(omap.origin[1]), float(omap.resolution)
    rows = np.repeat(np.arange(len(xy)), np.diff(indptr))
    clear = [box_clear(wall_sums(omap), ox, oy, res, *xy[i], *xy[j]) for i, j in zip(rows, indices, strict=True)]
    assert any(clear) and (not all(clear) or name.startswith("open"))  # both paths ran (open maps: no walls inside)
    assert (fast < 0).any() or name.startswith("open")  # some links are cut by walls


def test_still_links_keep_their_margins_while_others_move():
    """A medium reuses the margins of pairs that stood still: step after step they equal a fresh computation."""
    omap = resolve_map("office-32x32")
    medium = make_medium("multi-wall", LinkBudget(r_c=2.0, exponent=2.0, wall_db=6.9), omap)
    rng = np.random.default_rng(11)
    xy = scattered(omap, 600, seed=5)
    for step in range(12):
        if step == 6:
            xy = np.vstack([xy, scattered(omap, 40, seed=step)])  # new robots join (the table grows)
        else:
            movers = rng.random(len(xy)) < (0.05 if step % 3 else 1.0)
            xy = xy.copy()
            xy[movers] += rng.uniform(-0.1, 0.1, (movers.sum(), 2))
        table = medium.update(xy).geometric
        fresh = candidate_margins(table.xy, table.indptr, table.indices, table.dist, *NO_PREVIOUS,
                                  medium.hearing.plain())
        np.testing.assert_array_equal(table.link_margin, fresh)
