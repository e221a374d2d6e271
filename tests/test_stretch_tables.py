"""A quiet stretch's radio tables made of the last ones (only the moved robots' pairs anew) against the tables built
whole, entry by entry (amronet.algorithms.agent_assisted.stretch_links)."""

import functools

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from amronet.algorithms.agent_assisted.stretch_links import (
    FEW_MOVED,
    NO_MARGIN,
    Radio,
    moved_nodes,
    moved_radio,
    next_radio,
    rebuilt_radio,
)
from amronet.engine.radio import make_medium
from amronet.scenario.radio_spec import RadioSpec
from amronet.world.builtin import resolve_map

RADIOS = [("multi-wall", 4.0), ("multi-wall", 0.0), ("log-distance", 4.0)]  # walls and shadowing, walls, shadowing
SIDE = 32.0  # the office's side (m)


@functools.cache
def _medium(model, db):
    budget = RadioSpec(model=model, r_c=6.0, shadowing_db=db).link_budget()
    return make_medium(model, budget, resolve_map("office-32x32"), np.random.default_rng(3))


def _first(medium, xy, silent):
    """The radio as a stretch starts it: of the radio medium's table (as QuietStretch._radio builds it)."""
    table = medium.update(xy, None, silent if silent.shape[0] else None)
    near = table.geometric
    return tuple(Radio(medium.reach, table.indptr, table.indices, table.dist, NO_MARGIN, near.indptr, near.indices,
                       near.dist, near.xy, near.link_margin, medium.stretch_inputs, silent))


def _move(rng, xy, kind, count):
    """``xy`` with ``count`` robots moved: a step's jitter, far, back where a robot stood, onto another robot."""
    n = len(xy)
    here = xy.copy()
    who = rng.choice(n, min(count, n), replace=False)
    if kind == "jitter":
        here[who] += rng.normal(0.0, 0.4, (len(who), 2))
    elif kind == "far":
        here[who] = rng.uniform(0.0, SIDE, (len(who), 2))
    else:  # onto another robot (a pair 0 long)
        here[who] = xy[rng.integers(0, n, len(who))]
    return here


def _assert_same(got, want, step):
    assert got[0] == want[0], step
    assert got[1][0] == want[1][0]
    for k, name in enumerate(Radio._fields):
        if k in (0, 10):  # (r, the hearing inputs: passed on)
            continue
        a, b = got[1][k], want[1][k]
        assert a.dtype == b.dtype and a.shape == b.shape, (step, name, a.dtype, b.dtype, a.shape, b.shape)
        np.testing.assert_array_equal(a, b, err_msg=f"step {step}: {name}")


@settings(max_examples=60, deadline=None)
@given(radio=st.sampled_from(RADIOS), n=st.integers(2, 70), seed=st.integers(0, 2**32 - 1),
       silent=st.sampled_from([0.0, 0.15, 1.0]),
       steps=st.lists(st.tuples(st.sampled_from(["jitter", "far", "onto"]), st.integers(0, 8)), min_size=1,
                      max_size=6))
def test_the_tables_made_of_the_last_ones_are_those_built_whole(radio, n, seed, silent, steps):
    # step after step from the radio medium's table, a few robots moving (none, or more than a few), some failed (or
    # none): the tables of the still robots' entries and the moved robots' pairs made anew are those built whole,
    # every array equal, entries in the same order, of the same types
    medium = _medium(*radio)
    rng = np.random.default_rng(seed)
    xy = rng.uniform(0.0, SIDE, (n, 2))
    mute = rng.random(n) < silent
    radio = _first(medium, xy, mute if mute.any() else np.zeros(0, dtype=bool))
    for step, (kind, count) in enumerate(steps):
        here = _move(rng, xy, kind, count)
        moved = moved_nodes(here, xy)
        assert np.array_equal(moved, np.flatnonzero((here != xy).any(axis=1)))
        got = moved_radio(here.copy(), radio, moved)
        want = rebuilt_radio(here.copy(), radio, np.zeros(n, dtype=np.int64), False)
        _assert_same(got, want, step)
        picked = next_radio(here, radio, np.zeros(n, dtype=np.int64), False)
        _assert_same(picked, want, step)
        radio, xy = got[1], here


@pytest.mark.parametrize(("model", "db"), RADIOS)
def test_many_steps_of_the_agents_alone_keep_the_tables_built_whole(model, db):
    # a stretch's steps: three agents moving, every other robot still, some failed; a long chain of tables made of the
    # last ones, each as built whole
    medium = _medium(model, db)
    rng = np.random.default_rng(5)
    n = 120
    xy = rng.uniform(0.0, SIDE, (n, 2))
    radio = _first(medium, xy, rng.random(n) < 0.1)
    agents = np.array([7, 60, 119])
    changed = 0
    for step in range(60):
        here = xy.copy()
        here[agents] = np.clip(here[agents] + rng.normal(0.0, 0.5, (3, 2)), 0.0, SIDE)
        want = rebuilt_radio(here.copy(), radio, np.zeros(n, dtype=np.int64), False)
        got = next_radio(here, radio, np.zeros(n, dtype=np.int64), False)
        _assert_same(got, want, step)
        changed += not np.array_equal(got[1][6], radio[6])
        radio, xy = got[1], here
    assert 3 * FEW_MOVED[1] <= n * FEW_MOVED[0]  # (the tables were made of the last ones)
    assert changed > 10  # (pairs came and went)


def test_a_non_finite_position_gives_no_table():
    medium = _medium("multi-wall", 4.0)
    xy = np.random.default_rng(2).uniform(0.0, SIDE, (30, 2))
    radio = _first(medium, xy, np.zeros(0, dtype=bool))
    here = xy.copy()
    here[4, 1] = np.nan
    ok, same = moved_radio(here, radio, moved_nodes(here, xy))
    assert not ok and all(np.array_equal(a, b) for a, b in zip(same[1:10], radio[1:10], strict=True))
    assert not next_radio(here, radio, np.zeros(30, dtype=np.int64), False)[0]


def test_a_pair_r_apart_is_in_the_table_as_the_search_has_it():
    # a robot moving to exactly r from a still one (dx * dx + dy * dy == r * r), and one a hair farther
    medium = _medium("multi-wall", 4.0)
    r = medium.reach
    xy = np.random.default_rng(4).uniform(0.0, SIDE, (40, 2))
    xy[1] = (r, 5.0)
    xy[2] = (np.nextafter(r, np.inf), 9.0)
    radio = _first(medium, xy, np.zeros(0, dtype=bool))
    here = xy.copy()
    here[0] = (0.0, 5.0)
    here[3] = (0.0, 9.0)
    got = moved_radio(here.copy(), radio, moved_nodes(here, xy))
    _assert_same(got, rebuilt_radio(here.copy(), radio, np.zeros(40, dtype=np.int64), False), 0)
    row = got[1][6][got[1][5][0]:got[1][5][1]]
    assert 1 in row and 2 not in got[1][6][got[1][5][3]:got[1][5][4]]
