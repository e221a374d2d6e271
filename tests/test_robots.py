"""Tests of amronet.engine.robots: robot kinds, state codes and the Swarm arrays."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from amronet.engine.robots import (
    AMIGOBOT,
    BEBOT,
    DEPLOYED_STATES,
    MOBILE_STATES,
    PIONEER,
    ROBOT_MODELS,
    ROLE_NAMES,
    SETTLING_STATES,
    STATE_NAMES,
    RobotModel,
    Role,
    State,
    Swarm,
    state_lookup,
)

ALL_STATES = (State.BASE, State.EXPLORE, State.REFERENCE, State.TRIANGLE, State.TRIANGLE_SETTLED, State.AGENT,
              State.DROPPED, State.FAILED, State.RELOCATING, State.STRIP)
ROW_FIELDS = ("xy", "heading", "role", "state", "status", "radius", "max_speed", "model", "distance")
CUSTOM = RobotModel("custom", radius=0.1, max_speed=0.3, sensor_beams=4, sensor_range=0.5)


def small_swarm() -> Swarm:
    """Base 0, three routers, two agents of base 0: six robots, three models."""
    return Swarm.build([
        (AMIGOBOT, Role.BASE, State.BASE, np.array([[0.0, 0.0]]), np.array([0])),
        (BEBOT, Role.ROUTER, State.EXPLORE, np.array([[0.1, 0.2], [0.3, 0.4], [0.5, 0.6]]), np.full(3, -1)),
        (PIONEER, Role.AGENT, State.AGENT, np.array([[1.0, 1.0], [2.0, 2.0]]), np.array([0, 0])),
    ])


def assert_same_arrays(a: Swarm, b: Swarm) -> None:
    assert a.models == b.models
    for f in ROW_FIELDS:
        np.testing.assert_array_equal(getattr(a, f), getattr(b, f), err_msg=f)
        assert getattr(a, f).dtype == getattr(b, f).dtype, f


# --- robot kinds ------------------------------------------------------------------------------------------


def test_bebot_router_has_the_paper_values() -> None:
    assert BEBOT == RobotModel("bebot", radius=0.045, max_speed=0.2, sensor_beams=12, sensor_range=0.14)


def test_pioneer_agent_has_the_paper_values() -> None:
    assert PIONEER.name == "pioneer"
    assert PIONEER.sensor_beams == 16
    assert PIONEER.sensor_range == 2.0
    assert PIONEER.max_speed == 0.5
    assert PIONEER.radius > BEBOT.radius


def test_amigobot_base_node_is_immobile() -> None:
    assert AMIGOBOT.name == "amigobot"
    assert AMIGOBOT.max_speed == 0.0
    assert AMIGOBOT.radius > 0
    assert AMIGOBOT.sensor_beams >= 1
    assert AMIGOBOT.sensor_range > 0


def test_robot_kinds_are_registered_under_their_names() -> None:
    assert ROBOT_MODELS == {"pioneer": PIONEER, "bebot": BEBOT, "amigobot": AMIGOBOT}
    for name, kind in ROBOT_MODELS.items():
        assert kind.name == name


def test_robot_kind_is_frozen() -> None:
    with pytest.raises(dataclasses.FrozenInstanceError):
        BEBOT.radius = 1.0  # type: ignore[misc]


# --- kind and state codes ---------------------------------------------------------------------------------


def test_kind_codes_index_the_kind_names() -> None:
    assert ROLE_NAMES[Role.BASE] == "base"
    assert ROLE_NAMES[Role.ROUTER] == "router"
    assert ROLE_NAMES[Role.AGENT] == "agent"
    assert sorted((Role.BASE, Role.ROUTER, Role.AGENT)) == list(range(len(ROLE_NAMES)))


def test_state_codes_index_the_state_names() -> None:
    assert STATE_NAMES[State.BASE] == "base"
    assert STATE_NAMES[State.EXPLORE] == "explore"
    assert STATE_NAMES[State.REFERENCE] == "reference"
    assert STATE_NAMES[State.TRIANGLE] == "triangle"
    assert STATE_NAMES[State.TRIANGLE_SETTLED] == "triangle-settled"
    assert STATE_NAMES[State.AGENT] == "agent"
    assert STATE_NAMES[State.DROPPED] == "dropped"
    assert STATE_NAMES[State.FAILED] == "failed"
    assert STATE_NAMES[State.RELOCATING] == "relocating"
    assert STATE_NAMES[State.STRIP] == "strip"
    assert sorted(ALL_STATES) == list(range(len(STATE_NAMES)))
    assert len(set(STATE_NAMES)) == len(STATE_NAMES)


def test_codes_are_plain_ints_that_fit_int8() -> None:
    for code in (*ALL_STATES, Role.BASE, Role.ROUTER, Role.AGENT):
        assert type(code) is int
        assert -128 <= code <= 127


def test_every_state_is_deployed_mobile_or_silent() -> None:
    assert set(DEPLOYED_STATES) == {State.BASE, State.REFERENCE, State.TRIANGLE_SETTLED}
    assert set(MOBILE_STATES) == {State.EXPLORE, State.TRIANGLE, State.AGENT, State.RELOCATING, State.STRIP}
    assert not set(DEPLOYED_STATES) & set(MOBILE_STATES)
    silent = {State.DROPPED, State.FAILED}  # still, and relaying nothing
    assert set(DEPLOYED_STATES) | set(MOBILE_STATES) | silent == set(ALL_STATES)


def test_relaying_leaves_out_agents_and_silent_routers() -> None:
    sw = Swarm.build([(BEBOT, Role.ROUTER, State.REFERENCE, np.zeros((4, 2)), np.zeros(4)),
                      (PIONEER, Role.AGENT, State.AGENT, np.zeros((1, 2)), np.zeros(1))])
    sw.state[1], sw.state[2] = State.DROPPED, State.FAILED
    assert sw.relaying.tolist() == [True, False, False, True, False]
    assert sw.deployed.tolist() == [True, False, False, True, False]


def test_settling_states_are_the_mobile_router_states() -> None:
    assert set(SETTLING_STATES) == {State.EXPLORE, State.TRIANGLE}
    assert set(SETTLING_STATES) <= set(MOBILE_STATES)


@given(st.sets(st.sampled_from(ALL_STATES)))
def test_state_lookup_is_a_membership_table(states: set[int]) -> None:
    table = state_lookup(tuple(sorted(states)))
    assert table.shape == (len(STATE_NAMES),)
    assert table.dtype == bool
    for code in ALL_STATES:
        assert table[code] == (code in states)


def test_state_lookup_is_cached_and_read_only() -> None:
    table = state_lookup(DEPLOYED_STATES)
    assert state_lookup(DEPLOYED_STATES) is table
    assert not table.flags.writeable
    with pytest.raises(ValueError, match="read-only"):
        table[State.EXPLORE] = True


# --- Swarm.build ------------------------------------------------------------------------------------------


def test_build_gives_ids_in_group_order() -> None:
    swarm = small_swarm()
    assert len(swarm) == 6
    np.testing.assert_array_equal(swarm.role, [Role.BASE, Role.ROUTER, Role.ROUTER, Role.ROUTER, Role.AGENT,
                                               Role.AGENT])
    np.testing.assert_array_equal(swarm.state, [State.BASE, *[State.EXPLORE] * 3, *[State.AGENT] * 2])
    np.testing.assert_array_equal(swarm.status, [0, -1, -1, -1, 0, 0])
    np.testing.assert_array_equal(swarm.xy, [[0, 0], [0.1, 0.2], [0.3, 0.4], [0.5, 0.6], [1, 1], [2, 2]])


def test_build_sets_per_robot_model_radius_and_speed() -> None:
    swarm = small_swarm()
    assert swarm.models == (AMIGOBOT, BEBOT, PIONEER)
    np.testing.assert_array_equal(swarm.model, [0, 1, 1, 1, 2, 2])
    np.testing.assert_array_equal(swarm.radius, [AMIGOBOT.radius, *[BEBOT.radius] * 3, *[PIONEER.radius] * 2])
    np.testing.assert_array_equal(swarm.max_speed,
                                  [AMIGOBOT.max_speed, *[BEBOT.max_speed] * 3, *[PIONEER.max_speed] * 2])
    for i in range(len(swarm)):
        assert swarm.radius[i] == swarm.models[swarm.model[i]].radius


def test_build_starts_with_zero_heading_and_distance() -> None:
    swarm = small_swarm()
    np.testing.assert_array_equal(swarm.heading, np.zeros(6))
    np.testing.assert_array_equal(swarm.distance, np.zeros(6))


def test_build_uses_the_documented_dtypes_and_shapes() -> None:
    swarm = small_swarm()
    assert swarm.xy.shape == (6, 2) and swarm.xy.dtype == float
    assert swarm.role.dtype == np.int8
    assert swarm.state.dtype == np.int8
    assert swarm.status.dtype == np.int32
    assert swarm.model.dtype == np.int8
    for f in ("heading", "radius", "max_speed", "distance"):
        assert getattr(swarm, f).shape == (6,), f
        assert getattr(swarm, f).dtype == float, f


def test_build_shares_a_model_between_groups_of_the_same_kind() -> None:
    swarm = Swarm.build([
        (BEBOT, Role.ROUTER, State.EXPLORE, np.zeros((2, 2)), np.full(2, -1)),
        (AMIGOBOT, Role.BASE, State.BASE, np.ones((1, 2)), np.array([0])),
        (BEBOT, Role.ROUTER, State.REFERENCE, np.full((1, 2), 2.0), np.array([0])),
    ])
    assert swarm.models == (BEBOT, AMIGOBOT)
    np.testing.assert_array_equal(swarm.model, [0, 0, 1, 0])
    np.testing.assert_array_equal(swarm.state, [State.EXPLORE, State.EXPLORE, State.BASE, State.REFERENCE])


def test_build_of_no_groups_is_an_empty_swarm() -> None:
    swarm = Swarm.build([])
    assert len(swarm) == 0
    assert swarm.models == ()
    assert swarm.xy.shape == (0, 2)
    for f in ROW_FIELDS:
        assert len(getattr(swarm, f)) == 0, f


# --- in_states and deployed -------------------------------------------------------------------------------


@given(
    st.lists(st.sampled_from(ALL_STATES), max_size=30),
    st.sets(st.sampled_from(ALL_STATES)),
)
def test_in_states_matches_isin(codes: list[int], states: set[int]) -> None:
    n = len(codes)
    swarm = Swarm.build([(BEBOT, Role.ROUTER, State.EXPLORE, np.zeros((n, 2)), np.full(n, -1))])
    swarm.state[:] = codes
    mask = swarm.in_states(tuple(states))
    assert mask.dtype == bool
    np.testing.assert_array_equal(mask, np.isin(np.asarray(codes, dtype=int), list(states)))


def test_deployed_is_base_reference_and_triangle_settled() -> None:
    n = len(ALL_STATES)
    swarm = Swarm.build([(BEBOT, Role.ROUTER, State.EXPLORE, np.zeros((n, 2)), np.full(n, -1))])
    swarm.state[:] = ALL_STATES
    expected = [s in (State.BASE, State.REFERENCE, State.TRIANGLE_SETTLED) for s in ALL_STATES]
    np.testing.assert_array_equal(swarm.deployed, expected)
    swarm.state[:] = State.EXPLORE
    assert not swarm.deployed.any()


# --- concat -----------------------------------------------------------------------------------------------


def test_concat_puts_the_parts_one_block_after_another() -> None:
    a = small_swarm()
    b = small_swarm()
    b.xy += 10.0
    b.heading[:] = 1.5
    b.distance[:] = np.arange(6)
    b.status[:] = 7
    joined = Swarm.concat([a, b, a])
    assert len(joined) == 18
    assert joined.models == a.models
    for f in ROW_FIELDS:
        np.testing.assert_array_equal(getattr(joined, f)[:6], getattr(a, f), err_msg=f)
        np.testing.assert_array_equal(getattr(joined, f)[6:12], getattr(b, f), err_msg=f)
        np.testing.assert_array_equal(getattr(joined, f)[12:], getattr(a, f), err_msg=f)
        assert getattr(joined, f).dtype == getattr(a, f).dtype, f


def test_concat_copies_the_parts() -> None:
    a = small_swarm()
    joined = Swarm.concat([a, small_swarm()])
    joined.xy[0] = (9.0, 9.0)
    joined.state[0] = State.EXPLORE
    np.testing.assert_array_equal(a.xy[0], (0.0, 0.0))
    assert a.state[0] == State.BASE


def test_concat_refuses_different_robot_models() -> None:
    a = small_swarm()
    other = Swarm.build([(CUSTOM, Role.ROUTER, State.EXPLORE, np.zeros((1, 2)), np.array([-1]))])
    with pytest.raises(ValueError, match="different robot models"):
        Swarm.concat([a, other])


def test_concat_refuses_the_same_models_in_another_order() -> None:
    a = Swarm.build([
        (BEBOT, Role.ROUTER, State.EXPLORE, np.zeros((1, 2)), np.array([-1])),
        (PIONEER, Role.AGENT, State.AGENT, np.zeros((1, 2)), np.array([0])),
    ])
    b = Swarm.build([
        (PIONEER, Role.AGENT, State.AGENT, np.zeros((1, 2)), np.array([0])),
        (BEBOT, Role.ROUTER, State.EXPLORE, np.zeros((1, 2)), np.array([-1])),
    ])
    with pytest.raises(ValueError, match="different robot models"):
        Swarm.concat([a, b])


def test_concat_of_one_part_equals_it() -> None:
    a = small_swarm()
    assert_same_arrays(Swarm.concat([a]), a)


# --- rows and copy ----------------------------------------------------------------------------------------


def test_rows_are_views_and_writes_go_through() -> None:
    swarm = small_swarm()
    part = swarm.rows(slice(1, 4))
    assert len(part) == 3
    assert part.models == swarm.models
    for f in ROW_FIELDS:
        assert np.shares_memory(getattr(part, f), getattr(swarm, f)), f
        np.testing.assert_array_equal(getattr(part, f), getattr(swarm, f)[1:4], err_msg=f)
    part.xy[0] = (5.0, 6.0)
    part.state[1] = State.REFERENCE
    part.status[2] = 4
    part.heading[:] = 0.25
    part.distance += 1.0
    np.testing.assert_array_equal(swarm.xy[1], (5.0, 6.0))
    assert swarm.state[2] == State.REFERENCE
    assert swarm.status[3] == 4
    np.testing.assert_array_equal(swarm.heading, [0, 0.25, 0.25, 0.25, 0, 0])
    np.testing.assert_array_equal(swarm.distance, [0, 1, 1, 1, 0, 0])


def test_writes_to_the_swarm_show_in_its_rows() -> None:
    swarm = small_swarm()
    part = swarm.rows(slice(4, None))
    swarm.xy[5] = (-1.0, -2.0)
    np.testing.assert_array_equal(part.xy[1], (-1.0, -2.0))


def test_copy_is_equal_and_independent() -> None:
    swarm = small_swarm()
    dup = swarm.copy()
    assert_same_arrays(dup, swarm)
    for f in ROW_FIELDS:
        assert not np.shares_memory(getattr(dup, f), getattr(swarm, f)), f
    dup.xy[:] = 7.0
    dup.state[:] = State.REFERENCE
    dup.distance[:] = 3.0
    np.testing.assert_array_equal(swarm.xy[0], (0.0, 0.0))
    assert swarm.state[1] == State.EXPLORE
    assert not swarm.distance.any()
    swarm.heading[:] = 1.0
    assert not dup.heading.any()


# --- extend -----------------------------------------------------------------------------------------------


def test_extend_returns_the_new_ids_and_keeps_existing_rows() -> None:
    swarm = small_swarm()
    swarm.heading[:] = np.linspace(0, 1, 6)
    swarm.distance[:] = np.arange(6)
    before = swarm.copy()
    ids = swarm.extend(BEBOT, Role.ROUTER, State.EXPLORE, np.array([[3.0, 3.0], [4.0, 4.0]]), np.array([0, 1]))
    np.testing.assert_array_equal(ids, [6, 7])
    assert len(swarm) == 8
    assert swarm.models == before.models
    for f in ROW_FIELDS:
        np.testing.assert_array_equal(getattr(swarm, f)[:6], getattr(before, f), err_msg=f)
        assert getattr(swarm, f).dtype == getattr(before, f).dtype, f
        assert len(getattr(swarm, f)) == 8, f


def test_extend_fills_the_new_rows() -> None:
    swarm = small_swarm()
    ids = swarm.extend(BEBOT, Role.ROUTER, State.REFERENCE, np.array([[3.0, 3.5], [4.0, 4.5]]), np.array([0, 1]),
                       heading=np.array([0.5, -0.5]))
    np.testing.assert_array_equal(swarm.xy[ids], [[3.0, 3.5], [4.0, 4.5]])
    np.testing.assert_array_equal(swarm.heading[ids], [0.5, -0.5])
    np.testing.assert_array_equal(swarm.role[ids], [Role.ROUTER] * 2)
    np.testing.assert_array_equal(swarm.state[ids], [State.REFERENCE] * 2)
    np.testing.assert_array_equal(swarm.status[ids], [0, 1])
    np.testing.assert_array_equal(swarm.radius[ids], [BEBOT.radius] * 2)
    np.testing.assert_array_equal(swarm.max_speed[ids], [BEBOT.max_speed] * 2)
    np.testing.assert_array_equal(swarm.model[ids], [swarm.models.index(BEBOT)] * 2)
    np.testing.assert_array_equal(swarm.distance[ids], [0.0, 0.0])


def test_extend_without_heading_gives_zero_headings() -> None:
    swarm = small_swarm()
    swarm.heading[:] = 2.0
    ids = swarm.extend(PIONEER, Role.AGENT, State.AGENT, np.array([[1.0, 2.0]]), np.array([0]))
    np.testing.assert_array_equal(swarm.heading[ids], [0.0])
    np.testing.assert_array_equal(swarm.heading[:6], np.full(6, 2.0))


def test_extend_appends_a_new_model() -> None:
    swarm = small_swarm()
    ids = swarm.extend(CUSTOM, Role.ROUTER, State.EXPLORE, np.array([[1.0, 1.0]]), np.array([-1]))
    assert swarm.models == (AMIGOBOT, BEBOT, PIONEER, CUSTOM)
    np.testing.assert_array_equal(swarm.model, [0, 1, 1, 1, 2, 2, 3])
    assert swarm.radius[ids[0]] == CUSTOM.radius
    assert swarm.max_speed[ids[0]] == CUSTOM.max_speed


def test_extend_reallocates_the_arrays() -> None:
    swarm = small_swarm()
    old = {f: getattr(swarm, f) for f in ROW_FIELDS}
    view = swarm.rows(slice(0, 6))
    swarm.extend(BEBOT, Role.ROUTER, State.EXPLORE, np.array([[1.0, 1.0]]), np.array([-1]))
    for f in ROW_FIELDS:
        assert getattr(swarm, f) is not old[f], f
        assert not np.shares_memory(getattr(swarm, f), old[f]), f
    view.xy[0] = (8.0, 8.0)  # a view held across extend no longer reaches the swarm
    np.testing.assert_array_equal(swarm.xy[0], (0.0, 0.0))


def test_extend_accepts_a_flat_point_and_no_robots() -> None:
    swarm = small_swarm()
    ids = swarm.extend(BEBOT, Role.ROUTER, State.EXPLORE, [1.0, 2.0], [-1])
    np.testing.assert_array_equal(ids, [6])
    np.testing.assert_array_equal(swarm.xy[6], (1.0, 2.0))
    ids = swarm.extend(BEBOT, Role.ROUTER, State.EXPLORE, np.zeros((0, 2)), np.zeros(0))
    assert len(ids) == 0
    assert len(swarm) == 7


@settings(max_examples=40, deadline=None)
@given(st.lists(st.integers(min_value=0, max_value=4), min_size=1, max_size=6))
def test_repeated_extend_keeps_every_array_the_same_length(batches: list[int]) -> None:
    swarm = small_swarm()
    expected_ids: list[int] = []
    for n in batches:
        start = len(swarm)
        ids = swarm.extend(BEBOT, Role.ROUTER, State.EXPLORE, np.full((n, 2), 0.5), np.full(n, -1))
        np.testing.assert_array_equal(ids, np.arange(start, start + n))
        expected_ids.extend(ids.tolist())
    assert len(swarm) == 6 + sum(batches)
    for f in ROW_FIELDS:
        assert len(getattr(swarm, f)) == len(swarm), f
    assert swarm.models == (AMIGOBOT, BEBOT, PIONEER)
    np.testing.assert_array_equal(swarm.role[expected_ids], np.full(len(expected_ids), Role.ROUTER))
