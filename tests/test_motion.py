import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from amronet.engine.motion import avoidance_heading, integrate, path_clear, random_walk
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
    scans[2, 0] = 0.02  # robot 2 sees a wall straight ahead
    who = np.array([0, 1, 3])
    a, b = np.zeros(4), np.zeros(4)
    random_walk(a, who, scans, 0.14, np.array([False, True, False]), np.random.default_rng(1), 0.1)
    random_walk(b, who, scans, 0.14, np.array([False, True, False]), np.random.default_rng(1), 0.1)
    assert np.array_equal(a, b)
    assert abs(a[0]) < 0.5  # keeps going, with a little noise
    assert a[2] == 0.0  # not walking: untouched
    assert abs(abs(a[3]) - np.pi) < 0.5  # turned around


def test_goal_steering_heads_for_goal_keeps_anchors_and_gives_up():
    from amronet.algorithms.common.goto import GoalSteering

    xy = np.array([[0.0, 0.0], [0.0, 0.9], [5.0, 5.0]])
    heading = np.zeros(3)
    steering = GoalSteering(3, n_anchors=1, give_up_steps=3)
    steering.start(np.array([0]), np.array([[0.0, 1.0]]), np.array([[-1]]))
    length, done = steering.steer(np.array([0]), xy, heading, np.full((1, 8), 0.14), 0.14, np.array([0.1]), 1.0)
    assert heading[0] == np.pi / 2 and length[0] == 0.1 and not done[0]
    # an anchor the move would leave behind: the robot refuses the move, and gives up after 3 blocked steps
    steering.start(np.array([0]), np.array([[0.0, 3.0]]), np.array([[2]]))
    xy[0] = [5.0, 4.0]
    steering.goal[0] = [5.0, 3.0]
    results = [steering.steer(np.array([0]), xy, heading, np.full((1, 8), 0.14), 0.14, np.array([0.1]), 1.0)
               for _ in range(5)]
    assert all(r[0][0] == 0.0 for r in results)
    assert [bool(r[1][0]) for r in results] == [False, False, False, True, True]  # first step sets the baseline
