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
