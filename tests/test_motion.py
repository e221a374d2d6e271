import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from amronet.motion import avoidance_heading, go_to_goal, integrate, path_clear, random_walk
from amronet.world.space import clearance
from helpers import box_map, diagonal_wall_map


def test_path_clear_refuses_crossing_a_one_pixel_wall():
    omap = box_map(walls=[(slice(None), slice(50, 51))])
    start = np.array([[2.3, 2.5], [2.3, 2.5]])
    end = np.array([[2.8, 2.5], [2.4, 2.5]])
    assert path_clear(omap, start, end, np.array([0.01, 0.01])).tolist() == [False, True]


@settings(max_examples=60, deadline=None)
@given(st.floats(0.2, 2.8), st.floats(0.2, 2.8), st.floats(-np.pi, np.pi), st.floats(0.01, 0.6))
def test_moves_never_cross_the_diagonal_wall(x, y, angle, length):
    omap = diagonal_wall_map()
    start = np.array([[x, y]])
    if not omap.is_free(start)[0]:
        return
    end = start + length * np.array([[np.cos(angle), np.sin(angle)]])
    xy = start.copy()
    integrate(omap, xy, np.array([0]), end - start, np.array([0.02]), bodies=False)
    side_before = np.sign(start[0, 1] - start[0, 0])
    side_after = np.sign(xy[0, 1] - xy[0, 0])
    assert side_before == side_after
    rows, cols = omap.world_to_cell(xy)
    assert clearance(omap)[rows[0], cols[0]] >= 0.02


def test_integrate_refuses_body_overlap():
    omap = box_map()
    xy = np.array([[2.0, 2.5], [2.2, 2.5]])
    radius = np.array([0.05, 0.05])
    refused = integrate(omap, xy, np.array([0]), np.array([[0.15, 0.0]]), radius)
    assert refused.tolist() == [True]
    assert xy[0].tolist() == [2.0, 2.5]
    refused = integrate(omap, xy, np.array([0]), np.array([[0.05, 0.0]]), radius)
    assert refused.tolist() == [False] and xy[0, 0] == 2.05


def test_avoidance_turns_away_from_what_is_ahead():
    scans = np.full((1, 4), 1.0)
    scans[0, 0] = 0.1  # something straight ahead
    escape, alarmed = avoidance_heading(np.zeros(1), scans, 1.0)
    assert alarmed[0] and abs(abs(escape[0]) - np.pi) < 1e-9
    scans = np.full((1, 4), 1.0)
    scans[0, 2] = 0.1  # behind only: not alarmed
    _, alarmed = avoidance_heading(np.zeros(1), scans, 1.0)
    assert not alarmed[0]


def test_random_walk_reproducible_and_bounces_when_blocked():
    scans = np.full((3, 8), 0.14)
    h = np.zeros(3)
    a = random_walk(h, scans, 0.14, np.array([False, True, False]), np.random.default_rng(1), 0.1)
    b = random_walk(h, scans, 0.14, np.array([False, True, False]), np.random.default_rng(1), 0.1)
    assert np.array_equal(a, b)
    assert abs(a[0]) < 0.5 and abs(a[2]) < 0.5


def test_go_to_goal_heads_for_goal_when_clear():
    xy = np.array([[0.0, 0.0]])
    heading = go_to_goal(xy, np.zeros(1), np.array([[0.0, 1.0]]), np.full((1, 8), 0.14), 0.14)
    assert heading[0] == np.pi / 2
