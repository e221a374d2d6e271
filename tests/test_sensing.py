import numpy as np
import pytest

from amronet.engine.radio import UnitDisk
from amronet.engine.sensing import beam_angles, range_scan
from helpers import box_map


def test_beam_angles_start_forward():
    a = beam_angles(4)
    assert np.allclose(a, [0, np.pi / 2, np.pi, 3 * np.pi / 2])


def test_ray_hits_wall_at_the_right_distance():
    omap = box_map(rows=100, cols=100, res=0.05)  # 5 m box, inner free x in [0.05, 4.95]
    xy = np.array([[2.5, 2.5]])
    scans = range_scan(omap, xy, np.zeros(1), np.array([0]), 4, 10.0)
    # east wall starts at x = 4.95 -> 2.45 m; sensing resolution is half a cell
    assert scans[0] == pytest.approx([2.45, 2.45, 2.45, 2.45], abs=0.03)


def test_max_range_when_nothing_is_near():
    omap = box_map()
    scans = range_scan(omap, np.array([[2.5, 2.5]]), np.array([0.3]), np.array([0]), 12, 0.14)
    assert np.all(scans == 0.14)


def test_other_robots_stop_beams():
    omap = box_map()
    xy = np.array([[2.5, 2.5], [2.6, 2.5]])
    radius = np.array([0.045, 0.045])
    for r_c in (1.0, 0.1):  # neighbours from the table, or from the k-d tree when the sensor reaches farther
        table = UnitDisk(r_c).update(xy)
        scans = range_scan(omap, xy, np.zeros(2), np.array([0, 1]), 4, 0.14, radius=radius, table=table)
        check_bodies(scans)


def check_bodies(scans):
    assert scans[0, 0] == pytest.approx(0.1 - 0.045, abs=1e-9)  # robot 0 sees robot 1 ahead
    assert scans[1, 2] == pytest.approx(0.1 - 0.045, abs=1e-9)  # robot 1 sees robot 0 behind
    assert scans[0, 2] == pytest.approx(0.14)


def test_one_pixel_wall_stops_rays():
    omap = box_map(walls=[(slice(None), slice(50, 51))])  # wall at x in [2.5, 2.55)
    scans = range_scan(omap, np.array([[2.0, 2.5]]), np.zeros(1), np.array([0]), 1, 5.0)
    assert scans[0, 0] == pytest.approx(0.5, abs=0.03)


def _cluttered_map():
    rng = np.random.default_rng(5)
    walls = [(slice(int(r), int(r) + 1 + int(h)), slice(int(c), int(c) + 1 + int(w)))
             for r, c, h, w in rng.integers(0, 90, size=(40, 4)) % [90, 90, 3, 3]]
    return box_map(rows=100, cols=100, res=0.047, origin=(-0.3, 0.2), walls=walls)


def test_every_beam_from_a_quiet_cell_reads_max_range():
    from amronet.engine.sensing import quiet_cells
    from amronet.world.space import clearance
    omap, max_range = _cluttered_map(), 0.14
    quiet = quiet_cells(omap, max_range)
    res = omap.resolution
    rows, cols = np.nonzero(quiet)
    assert quiet_cells(omap, max_range) is quiet and not quiet[omap.blocked].any()
    # more cells than the clearance's own early-out (clear - res >= range) holds: the test is not about those alone
    assert np.count_nonzero(quiet.astype(bool) & (clearance(omap) - res < max_range)) > 100
    rng = np.random.default_rng(0)
    pick = rng.integers(len(rows), size=4000)
    corner = np.array(omap.origin) + np.stack([cols[pick], rows[pick]], axis=1) * res
    xy = corner + rng.choice([0.0, 1e-12, 0.5, 1.0 - 1e-12], size=(4000, 2)) * res  # cell edges too
    heading = rng.uniform(-np.pi, np.pi, 4000)
    scans = range_scan(omap, xy, heading, np.arange(4000), 12, max_range)
    assert np.all(scans == max_range)


def test_the_ring_in_one_pass_is_the_grid_then_the_bodies_bit_for_bit():
    from numba import njit

    from amronet.engine.kernel_data import grid_of
    from amronet.engine.sensing import QuietRing, cast_rings, quiet_cells

    @njit
    def rings(grid, ring, xy, heading, radius, csr, out, cells):
        dirs = (np.empty(out.shape[1]), np.empty(out.shape[1]))
        who = np.arange(xy.shape[0])
        cast_rings(grid, ring, who, xy, heading, radius, radius.max(), True, csr, dirs, out,
                   (0.0, np.empty(xy.shape[0] + 1, np.int64), np.empty(csr[1].shape[0] + 1, np.int64), cells))

    omap, max_range = _cluttered_map(), 0.14
    rng = np.random.default_rng(1)
    free_rows, free_cols = np.nonzero(~omap.blocked)
    pick = rng.integers(len(free_rows), size=1500)
    xy = np.array(omap.origin) + (np.stack([free_cols[pick], free_rows[pick]], axis=1) + rng.random((1500, 2))) * \
        omap.resolution
    heading = rng.uniform(-np.pi, np.pi, 1500)
    radius = rng.choice([0.045, 0.165], size=1500)
    table = UnitDisk(1.0).update(xy)
    want = range_scan(omap, xy, heading, np.arange(1500), 12, max_range, radius=radius, table=table)
    got = np.empty_like(want)
    cells = np.empty(1500, np.uint8)
    quiet = quiet_cells(omap, max_range)
    rings(grid_of(omap), QuietRing(beam_angles(12), max_range, quiet), xy, heading, radius,
          (table.indptr, table.indices, table.dist), got, cells)
    assert (want < max_range).any(axis=1).mean() > 0.3  # walls and bodies seen by many
    np.testing.assert_array_equal(got, want)
    rows, cols = omap.world_to_cell(xy)
    np.testing.assert_array_equal(cells, quiet[rows, cols])  # each robot's cell flags, for its move
