"""Tests of amronet.engine.walls: the wall counter against a slow reference, explicit cases, early stop, leaps."""

from __future__ import annotations

import math

import numpy as np
from hypothesis import HealthCheck, assume, given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from amronet.engine.walls import count_walls, count_walls_many, wall_grid
from amronet.world.builtin import resolve_map
from amronet.world.occupancy import FREE, OCCUPIED, UNKNOWN, OccupancyMap

BIG = 10**6  # a limit that never stops the count


def ref_walls(wallgrid: np.ndarray, ox: float, oy: float, res: float, x0: float, y0: float, x1: float,
              y1: float) -> int:
    """Slow reference: runs of wall cells (and outside cells) whose *open* square the segment passes through.

    Every wall cell of the bounding box (plus one cell around it; outside the map every cell is a wall) is
    intersected with the segment in the parameter ``t in [0, 1]``; the non-empty open intervals are sorted and
    intervals that touch are merged: each merged group is one wall.
    """
    rows, cols = wallgrid.shape
    dx, dy = x1 - x0, y1 - y0
    if dx == 0 and dy == 0:
        r, c = math.floor((y0 - oy) / res), math.floor((x0 - ox) / res)
        return int(not (0 <= r < rows and 0 <= c < cols) or bool(wallgrid[r, c]))
    c0 = math.floor((min(x0, x1) - ox) / res) - 1
    c1 = math.floor((max(x0, x1) - ox) / res) + 1
    r0 = math.floor((min(y0, y1) - oy) / res) - 1
    r1 = math.floor((max(y0, y1) - oy) / res) + 1
    intervals = []
    for r in range(r0, r1 + 1):
        for c in range(c0, c1 + 1):
            if 0 <= r < rows and 0 <= c < cols and not wallgrid[r, c]:
                continue
            lo, hi, ok = 0.0, 1.0, True
            for p, d, a, b in ((x0, dx, ox + c * res, ox + (c + 1) * res), (y0, dy, oy + r * res, oy + (r + 1) * res)):
                if d == 0:
                    ok = ok and a < p < b
                else:
                    ta, tb = sorted(((a - p) / d, (b - p) / d))
                    lo, hi = max(lo, ta), min(hi, tb)
            if ok and lo < hi:
                intervals.append((lo, hi))
    intervals.sort()
    n, end = 0, -1.0
    for lo, hi in intervals:
        if lo > end + 1e-9:
            n += 1
        end = max(end, hi)
    return n


def make_map(cells: np.ndarray, res: float = 0.1, origin: tuple[float, float] = (0.0, 0.0)) -> OccupancyMap:
    return OccupancyMap("hand", float(res), (float(origin[0]), float(origin[1])), np.asarray(cells, dtype=np.int8))


def count(omap: OccupancyMap, a, b, limit: int = BIG, jump: np.ndarray | None = None) -> int:
    walls, j = wall_grid(omap)
    return int(count_walls(walls, j if jump is None else jump, float(omap.origin[0]), float(omap.origin[1]),
                           float(omap.resolution), float(a[0]), float(a[1]), float(b[0]), float(b[1]), limit))


def generic(omap: OccupancyMap, a, b, eps: float = 1e-9) -> bool:
    """The segment is in generic position: it passes no grid vertex within ``eps`` (in cell units) and neither
    end lies within ``eps`` of a grid line, and it does not run along a grid line (all measure-zero ties)."""
    res = omap.resolution
    ox, oy = omap.origin
    u0, v0 = (a[0] - ox) / res, (a[1] - oy) / res
    u1, v1 = (b[0] - ox) / res, (b[1] - oy) / res
    for w in (u0, v0, u1, v1):
        if abs(w - round(w)) < eps:
            return False
    du, dv = u1 - u0, v1 - v0
    length = math.hypot(du, dv)
    if length < 1e-6:
        return False  # a point (or nearly): test_zero_length_segment
    if (du == 0 and abs(u0 - round(u0)) < eps) or (dv == 0 and abs(v0 - round(v0)) < eps):
        return False
    for gu in range(math.floor(min(u0, u1)), math.ceil(max(u0, u1)) + 1):
        for gv in range(math.floor(min(v0, v1)), math.ceil(max(v0, v1)) + 1):
            t = min(max(((gu - u0) * du + (gv - v0) * dv) / (length * length), 0.0), 1.0)
            if math.hypot(u0 + t * du - gu, v0 + t * dv - gv) < eps:
                return False
    return True


# -- property tests against the reference ------------------------------------------------------------------
CELL = st.sampled_from([FREE, FREE, FREE, OCCUPIED, UNKNOWN])


@st.composite
def small_grids(draw):
    rows, cols = draw(st.integers(1, 8)), draw(st.integers(1, 8))
    cells = draw(arrays(np.int8, (rows, cols), elements=CELL))
    res = draw(st.sampled_from([0.05, 0.1, 0.25, 0.3, 0.5, 1.0]) | st.floats(0.01, 2.0))
    origin = (draw(st.floats(-10, 10)), draw(st.floats(-10, 10)))
    return make_map(cells, res, origin)


@st.composite
def open_grids(draw):
    """Larger grids of open space with a few wall blocks and unknown blobs: the counter leaps through them."""
    rows, cols = draw(st.integers(20, 45)), draw(st.integers(20, 45))
    cells = np.zeros((rows, cols), dtype=np.int8)
    for _ in range(draw(st.integers(0, 6))):
        r, c = draw(st.integers(0, rows - 1)), draw(st.integers(0, cols - 1))
        h, w = draw(st.integers(1, 8)), draw(st.integers(1, 8))
        cells[r:r + h, c:c + w] = draw(st.sampled_from([OCCUPIED, UNKNOWN, FREE]))
    res = draw(st.sampled_from([0.05, 0.1, 0.2]) | st.floats(0.02, 0.5))
    origin = (draw(st.floats(-10, 10)), draw(st.floats(-10, 10)))
    return make_map(cells, res, origin)


def endpoints(draw, omap: OccupancyMap, outside: float = 0.25):
    """Two points in the map's extent widened by ``outside`` of its size on every side (so some are outside).

    Drawn on a fine lattice shifted by an irrational fraction of its step, so that the simple numbers Hypothesis
    likes (0, 1/2, the extent's corners) do not all land on grid lines; ``generic`` rejects the rare ties left.
    """
    xmin, xmax, ymin, ymax = omap.extent
    w, h = xmax - xmin, ymax - ymin
    k = st.integers(0, 10**6)
    f = [(draw(k) + 0.5 * math.sqrt(2)) / 10**6 * (1 + 2 * outside) - outside for _ in range(4)]
    return [(xmin + f[0] * w, ymin + f[1] * h), (xmin + f[2] * w, ymin + f[3] * h)]


@settings(max_examples=300, deadline=None, suppress_health_check=[HealthCheck.filter_too_much])
@given(st.data())
def test_count_matches_reference_on_small_random_grids(data):
    omap = data.draw(small_grids())
    a, b = endpoints(data.draw, omap)
    assume(generic(omap, a, b))
    walls, _ = wall_grid(omap)
    expected = ref_walls(walls, *map(float, omap.origin), omap.resolution, *a, *b)
    assert count(omap, a, b) == expected
    limit = data.draw(st.integers(0, 4))
    assert count(omap, a, b, limit=limit) == min(expected, limit + 1)


@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.filter_too_much])
@given(st.data())
def test_count_matches_reference_with_leaps(data):
    omap = data.draw(open_grids())
    a, b = endpoints(data.draw, omap, outside=0.1)
    assume(generic(omap, a, b))
    walls, jump = wall_grid(omap)
    expected = ref_walls(walls, *map(float, omap.origin), omap.resolution, *a, *b)
    assert count(omap, a, b) == expected
    assert count(omap, a, b, jump=np.zeros_like(jump)) == expected


# -- explicit cases ------------------------------------------------------------------------------------------
def room_with_walls(wall_cols: list[slice], rows: int = 10, cols: int = 30) -> OccupancyMap:
    """A free strip of ``rows x cols`` cells of 0.1 m, origin (0, 0), with full-height walls at ``wall_cols``."""
    cells = np.zeros((rows, cols), dtype=np.int8)
    for s in wall_cols:
        cells[:, s] = OCCUPIED
    return make_map(cells)


def test_one_wall_is_one():
    omap = room_with_walls([slice(10, 11)])
    assert count(omap, (0.52, 0.53), (2.07, 0.48)) == 1
    assert count(omap, (0.52, 0.53), (0.97, 0.61)) == 0  # stops before the wall
    assert count(omap, (2.07, 0.48), (0.52, 0.53)) == 1  # either direction


def test_thick_wall_counts_once_two_walls_count_two():
    thick = room_with_walls([slice(10, 15)])
    assert count(thick, (0.52, 0.53), (2.07, 0.48)) == 1
    assert count(thick, (0.52, 0.13), (2.07, 0.88)) == 1  # diagonal through the block
    two = room_with_walls([slice(10, 11), slice(20, 23)])
    assert count(two, (0.52, 0.53), (2.57, 0.48)) == 2
    assert count(two, (2.57, 0.48), (0.52, 0.53)) == 2
    assert count(two, (0.52, 0.53), (1.57, 0.48)) == 1


def test_segment_ending_inside_a_wall_counts_it():
    omap = room_with_walls([slice(10, 15)])
    assert count(omap, (0.52, 0.53), (1.21, 0.44)) == 1
    assert count(omap, (1.21, 0.44), (1.33, 0.58)) == 1  # wholly inside


def test_along_a_wall_face_crosses_none():
    # a wall block of rows 4..5, columns 5..14 of 0.125 m cells (every border is exact in binary floating point):
    # its faces are y = 0.5, y = 0.75, x = 0.625, x = 1.875
    cells = np.zeros((12, 20), dtype=np.int8)
    cells[4:6, 5:15] = OCCUPIED
    omap = make_map(cells, res=0.125)
    for y in (0.5, 0.75):  # along the lower and upper face, past both ends of the wall
        assert count(omap, (0.23, y), (2.21, y)) == 0
        assert count(omap, (2.21, y), (0.23, y)) == 0
    for x in (0.625, 1.875):  # along the left and right face
        assert count(omap, (x, 0.13), (x, 1.37)) == 0
        assert count(omap, (x, 1.37), (x, 0.13)) == 0
    # on the border *inside* the block (wall on both sides) it is in the wall, and so is a line just off a face
    assert count(omap, (0.23, 0.625), (2.21, 0.625)) == 1
    assert count(omap, (0.23, 0.7), (2.21, 0.7)) == 1
    assert count(omap, (0.23, 0.75 + 1e-12), (2.21, 0.75 + 1e-12)) == 0
    assert count(omap, (0.23, 0.75 - 1e-12), (2.21, 0.75 - 1e-12)) == 1
    # a face shared with the map's outside: the bottom edge of the map is outside on one side only
    assert count(omap, (0.23, 0.0), (2.21, 0.0)) == 0
    # along the border between the two rows of two wall blocks with a gap: two walls
    cells2 = np.zeros((12, 20), dtype=np.int8)
    cells2[4:6, 2:6] = OCCUPIED
    cells2[4:6, 10:16] = OCCUPIED
    assert count(make_map(cells2, res=0.125), (0.07, 0.625), (2.31, 0.625)) == 2
    # the same with a non-binary cell size, on a border the grid itself computes: row 5 starts at oy + 5 * res
    omap3 = make_map(cells, res=0.3, origin=(0.3, 0.7))
    for k in (4, 6):
        y = 0.7 + k * 0.3
        assert (y - 0.7) / 0.3 == k  # exactly on the border in floating point
        assert count(omap3, (0.53, y), (6.07, y)) == 0
        assert count(omap3, (6.07, y), (0.53, y)) == 0


def test_outside_the_map_is_a_wall():
    omap = make_map(np.zeros((10, 10), dtype=np.int8), origin=(-0.5, -0.5))
    assert count(omap, (0.01, 0.02), (0.33, -0.27)) == 0
    assert count(omap, (0.01, 0.02), (0.83, -0.17)) == 1  # ends outside
    assert count(omap, (-0.93, 0.02), (0.83, 0.07)) == 2  # starts and ends outside: two runs
    assert count(omap, (-0.93, -0.71), (-0.62, -0.83)) == 1  # wholly outside
    # a wall cell on the edge of the map and the outside beyond it are one run
    cells = np.zeros((10, 10), dtype=np.int8)
    cells[:, 9] = OCCUPIED
    assert count(make_map(cells, origin=(-0.5, -0.5)), (0.01, 0.02), (0.83, -0.07)) == 1


def test_unknown_cells_are_walls():
    cells = np.zeros((10, 30), dtype=np.int8)
    cells[:, 10] = UNKNOWN
    cells[:, 20] = OCCUPIED
    assert count(make_map(cells), (0.52, 0.53), (2.57, 0.48)) == 2


def test_zero_length_segment():
    """A segment from a point to itself is in a wall exactly when the point is (two robots at one spot)."""
    cells = np.zeros((40, 40), dtype=np.int8)
    cells[:, 0] = OCCUPIED
    omap = make_map(cells, res=0.05)
    for p in [(0.0125, 1.01), (-0.3, 1.01)]:  # in a wall cell, outside the map
        assert count(omap, p, p) == 1
    for p in [(0.33, 0.33), (1.01, 1.01), (1.025, 1.025), (0.625, 0.525)]:  # free; the last three in open space
        assert count(omap, p, p) == 0, p


def test_limit_stops_early():
    omap = room_with_walls([slice(5, 6), slice(10, 11), slice(15, 16), slice(20, 21)])
    a, b = (0.12, 0.53), (2.57, 0.48)
    assert count(omap, a, b) == 4
    for limit in range(4):
        assert count(omap, a, b, limit=limit) == limit + 1
    for limit in (4, 5, 100):
        assert count(omap, a, b, limit=limit) == 4
    # count_walls_many: one limit per segment
    walls, jump = wall_grid(omap)
    many = count_walls_many(walls, jump, 0.0, 0.0, 0.1, np.array([a, a, b]), np.array([b, b, a]),
                            np.array([0, 2, BIG]))
    assert many.tolist() == [1, 3, 4]


def test_wall_grid_marks_occupied_and_unknown_and_is_cached():
    cells = np.array([[FREE, OCCUPIED], [UNKNOWN, FREE]], dtype=np.int8)
    omap = make_map(cells)
    walls, jump = wall_grid(omap)
    assert walls.tolist() == [[0, 1], [1, 0]]
    assert walls.dtype == np.uint8 and (jump >= 0).all()
    assert wall_grid(omap)[0] is walls
    assert not walls.flags.writeable and not jump.flags.writeable


def test_leaps_agree_with_zero_jump_on_a_real_map():
    omap = resolve_map("office-32x32")
    walls, jump = wall_grid(omap)
    assert jump.max() > 6 * omap.resolution  # the map has open space to leap through
    xmin, xmax, ymin, ymax = omap.extent
    rng = np.random.default_rng(7)
    n = 3000
    a = np.column_stack([rng.uniform(xmin - 1, xmax + 1, n), rng.uniform(ymin - 1, ymax + 1, n)])
    # half long segments anywhere, half short ones (a few metres), the radio's typical links
    b = np.where(np.arange(n)[:, None] < n // 2,
                 np.column_stack([rng.uniform(xmin - 1, xmax + 1, n), rng.uniform(ymin - 1, ymax + 1, n)]),
                 a + rng.normal(0, 3, (n, 2)))
    ox, oy, res = float(omap.origin[0]), float(omap.origin[1]), float(omap.resolution)
    limits = np.full(n, BIG)
    fast = count_walls_many(walls, jump, ox, oy, res, a, b, limits)
    slow = count_walls_many(walls, np.zeros_like(jump), ox, oy, res, a, b, limits)
    np.testing.assert_array_equal(fast, slow)
    assert fast.max() >= 3 and (fast == 0).any()  # the sample is not trivial
    # and with a limit, too
    limits = rng.integers(0, 4, n)
    limited = count_walls_many(walls, jump, ox, oy, res, a, b, limits)
    np.testing.assert_array_equal(limited, np.minimum(slow, limits + 1))
    # a sample of the short ones against the reference (its cost grows with the segment's bounding box)
    for k in range(n // 2, n, 15):
        if generic(omap, a[k], b[k]):
            assert fast[k] == ref_walls(walls, ox, oy, res, *a[k], *b[k]), (a[k], b[k])
