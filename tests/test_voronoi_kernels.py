"""The Voronoi baselines' compiled geometry against its references: NumPy's sums bit for bit, shapely to rounding,
hand-computed circles, and the obstacle memory's rules."""

import numpy as np
import pytest
import shapely

from amronet.algorithms.common.obstacle_memory import ObstacleMemory
from amronet.algorithms.common.polygons import Polygons, area_centroid, clip_each, disk_overlap, regular, to_shapely
from amronet.algorithms.minimax.kernels import enclosing_centres
from amronet.engine.table import NeighbourTable


def array_area_centroid(poly):
    """The array form the compiled :func:`area_centroid` replaced (NumPy sums over the padded width)."""
    xy = poly.xy
    valid = poly.valid()
    nxt = np.take_along_axis(xy, poly.following()[:, :, None], axis=1)
    cross = np.where(valid, xy[:, :, 0] * nxt[:, :, 1] - nxt[:, :, 0] * xy[:, :, 1], 0.0)
    area = 0.5 * cross.sum(axis=1)
    moment = ((xy + nxt) * cross[:, :, None]).sum(axis=1)
    mean = (xy * valid[:, :, None]).sum(axis=1) / np.maximum(poly.count, 1)[:, None]
    flat = np.abs(area) <= 1e-15
    with np.errstate(invalid="ignore", divide="ignore"):
        centroid = np.where(flat[:, None], mean, moment / (6.0 * np.where(flat, 1.0, area))[:, None])
    return area, centroid


@pytest.mark.parametrize("width", [3, 7, 8, 9, 15, 16, 17, 40, 127, 128, 129, 136, 200, 257, 600])
def test_area_and_centroid_are_numpys_sums_bit_for_bit(width):
    rng = np.random.default_rng(width)
    xy = rng.normal(size=(400, width, 2)) * rng.uniform(0.01, 100.0, (400, 1, 1))
    poly = Polygons(xy, rng.integers(0, width + 1, 400))
    area, centroid = area_centroid(poly)
    expect_area, expect_centroid = array_area_centroid(poly)
    assert np.array_equal(area, expect_area)
    assert np.array_equal(centroid, expect_centroid)


def _random_cells(m, seed):
    rng = np.random.default_rng(seed)
    poly = regular(m, 1.0, 32, 32 + 10)
    for _ in range(10):
        angle = rng.uniform(0, 2 * np.pi, m)
        poly = clip_each(poly, np.arange(m + 1), np.stack([np.cos(angle), np.sin(angle)], axis=1),
                         rng.uniform(-0.2, 1.0, m))
    return poly, rng


def test_disk_overlap_is_shapelys_intersection_area():
    cells, rng = _random_cells(500, 1)
    centres = rng.uniform(-0.5, 0.5, (500, 2))
    expect = shapely.area(shapely.intersection(to_shapely(cells), to_shapely(regular(500, 0.4, 32, 32), centres)))
    got = disk_overlap(cells, centres, 0.4, 32)
    np.testing.assert_allclose(got, expect, rtol=0, atol=1e-14)
    assert (expect > 0).sum() > 100 and (expect == 0).sum() > 10  # overlaps and misses both tried


def test_enclosing_centres_are_shapelys_minimum_bounding_circles():
    cells, _ = _random_cells(2000, 2)
    full = cells.count >= 3
    expect = shapely.get_coordinates(shapely.centroid(shapely.minimum_bounding_circle(to_shapely(cells)[full])))
    np.testing.assert_allclose(enclosing_centres(cells)[full], expect, rtol=0, atol=1e-12)
    assert (enclosing_centres(cells)[~full] == 0.0).all()


def test_enclosing_centre_of_an_obtuse_triangle_is_the_middle_of_its_longest_side():
    xy = np.zeros((2, 4, 2))
    xy[0, :3] = [(0.0, 0.0), (4.0, 0.0), (1.0, 0.5)]  # obtuse at (1, 0.5)
    xy[1, :3] = [(0.0, 0.0), (2.0, 0.0), (1.0, 1.5)]  # acute: the circumcentre
    centres = enclosing_centres(Polygons(xy, np.array([3, 3])))
    np.testing.assert_allclose(centres, [(2.0, 0.0), (1.0, 5.0 / 12.0)], atol=1e-15)


def _table(xy, pairs):
    rows = np.array([a for a, b in pairs] + [b for a, b in pairs], dtype=np.int64)
    cols = np.array([b for a, b in pairs] + [a for a, b in pairs], dtype=np.int64)
    order = np.lexsort((cols, rows))
    rows, cols = rows[order], cols[order]
    indptr = np.zeros(len(xy) + 1, dtype=np.int64)
    np.cumsum(np.bincount(rows, minlength=len(xy)), out=indptr[1:])
    return NeighbourTable(xy=xy.copy(), r=10.0, indptr=indptr, indices=cols.astype(np.int32),
                          dist=np.hypot(*(xy[rows] - xy[cols]).T))


def test_the_memory_drops_bodies_and_keeps_one_point_per_cell_in_a_ring():
    xy = np.array([(0.0, 0.0), (0.5, 0.0)])  # robot 1 stands 0.5 m ahead of robot 0
    radius = np.array([0.05, 0.05])
    memory = ObstacleMemory(2, 3, 0.1)
    table = _table(xy, [(0, 1)])
    heading = np.zeros(2)
    far = 1.0
    scans = np.full((1, 4), far)  # beams at 0, 90, 180 and 270 degrees
    scans[0, 0] = 0.45  # robot 1's body: not an obstacle
    scans[0, 1] = 0.31  # a wall at (0, 0.31)
    memory.remember(np.array([0]), scans, xy, heading, far, table, radius)
    assert memory.stored.tolist() == [1, 0]
    np.testing.assert_allclose(memory.points[0, 0], (0.0, 0.31), atol=1e-12)
    memory.remember(np.array([0]), scans, xy, heading, far, table, radius)  # the same cell again: not stored
    assert memory.stored[0] == 1
    for k, reach in enumerate((0.52, 0.74, 0.96)):  # three new cells: the ring of 3 wraps over the first
        scans[0, 1] = reach
        memory.remember(np.array([0]), scans, xy, heading, far, table, radius)
        assert memory.stored[0] == 2 + k
    np.testing.assert_allclose(memory.points[0, :, 1], (0.96, 0.52, 0.74), atol=1e-12)
    points, filled = memory.remembered()
    assert filled.tolist() == [3, 0] and points is memory.points
