"""Tests of amronet.engine.streams: per-run random streams of runs stepped together."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from amronet.engine.streams import RunStreams, draw_per_run, normal_then_uniform


def draw_mixed(rng: np.random.Generator, m: int) -> tuple[np.ndarray, ...]:
    """Several arrays of different types and shapes, drawn in a fixed order."""
    return rng.random(m), rng.normal(size=m), rng.integers(0, 1000, size=m), rng.random((m, 2))


def draw_one(rng: np.random.Generator, m: int) -> tuple[np.ndarray, ...]:
    return (rng.random(m),)


def make_streams(seeds: list[int], sizes: list[int]) -> RunStreams:
    starts = np.concatenate([[0], np.cumsum(sizes)]).astype(np.int64)
    return RunStreams([np.random.default_rng(s) for s in seeds], starts)


def expected_alone(seeds: list[int], sizes: list[int], steps: list[np.ndarray], draw) -> list[tuple[np.ndarray, ...]]:
    """What every run draws on its own, step after step, put at its robots' places in each step's ``who``."""
    starts = np.concatenate([[0], np.cumsum(sizes)])
    alone = [np.random.default_rng(s) for s in seeds]
    out = []
    for who in steps:
        run = np.searchsorted(starts, who, side="right") - 1
        parts: list[np.ndarray] | None = None
        for g, rng in enumerate(alone):
            mine = np.flatnonzero(run == g)
            # the run alone: its own robots that draw, in their order, through a plain generator
            local = who[mine] - starts[g]
            got = draw_per_run(rng, local, draw)
            if parts is None:
                parts = [np.zeros((len(who), *p.shape[1:]), dtype=p.dtype) for p in got]
            for p, q in zip(parts, got, strict=True):
                p[mine] = q
        out.append(tuple(parts))
    return out


@st.composite
def batches(draw_):
    sizes = draw_(st.lists(st.integers(min_value=0, max_value=6), min_size=1, max_size=5))
    seeds = draw_(st.lists(st.integers(min_value=0, max_value=2**32 - 1), min_size=len(sizes), max_size=len(sizes)))
    total = sum(sizes)
    steps = []
    for _ in range(draw_(st.integers(min_value=1, max_value=3))):
        if total:
            who = draw_(st.lists(st.integers(min_value=0, max_value=total - 1), unique=True, max_size=total))
        else:
            who = []
        steps.append(np.asarray(who, dtype=np.int64))
    return seeds, sizes, steps


# --- the batch gives every run its own numbers --------------------------------------------------------------


def draw_normal_uniform(rng: np.random.Generator, m: int) -> tuple[np.ndarray, ...]:
    return rng.standard_normal(m), rng.random(m)


@settings(max_examples=150, deadline=None)
@given(batches(), st.booleans())
def test_the_walkers_pair_of_draws_is_the_general_draw(batch, in_order) -> None:
    # normal_then_uniform fills each run's slices in place (robots in order) or goes the general way (not in order)
    seeds, sizes, steps = batch
    streams = make_streams(seeds, sizes)
    expected = expected_alone(seeds, sizes, [np.sort(w) if in_order else w for w in steps], draw_normal_uniform)
    for who, want in zip(steps, expected, strict=True):
        got = normal_then_uniform(streams, np.sort(who) if in_order else who)
        for g, w in zip(got, want, strict=True):
            assert g.dtype == np.float64
            np.testing.assert_array_equal(g, w)
    for g, rng in enumerate(streams.generators):  # every stream is where the runs alone have theirs
        alone = np.random.default_rng(seeds[g])
        for who in steps:
            m = np.count_nonzero((who >= sum(sizes[:g])) & (who < sum(sizes[: g + 1])))
            draw_normal_uniform(alone, m)
        assert rng.random() == alone.random()


def test_the_walkers_pair_from_one_generator() -> None:
    a, b = np.random.default_rng(4), np.random.default_rng(4)
    normal, uniform = normal_then_uniform(a, np.array([7, 2, 5]))
    np.testing.assert_array_equal(normal, b.standard_normal(3))
    np.testing.assert_array_equal(uniform, b.random(3))


@settings(max_examples=150, deadline=None)
@given(batches())
def test_every_run_gets_the_numbers_it_would_draw_alone(batch) -> None:
    seeds, sizes, steps = batch
    streams = make_streams(seeds, sizes)
    expected = expected_alone(seeds, sizes, steps, draw_mixed)
    for who, want in zip(steps, expected, strict=True):
        got = draw_per_run(streams, who, draw_mixed)
        assert len(got) == len(want)
        for g, w in zip(got, want, strict=True):
            assert g.dtype == w.dtype
            assert g.shape == w.shape
            np.testing.assert_array_equal(g, w)


@settings(max_examples=100, deadline=None)
@given(batches())
def test_sorted_and_shuffled_who_give_each_robot_the_run_order_numbers(batch) -> None:
    seeds, sizes, steps = batch
    who = np.sort(steps[0])
    sorted_out = make_streams(seeds, sizes).draw(who, draw_one)[0]
    # the same robots asked in reverse: each run's numbers go to its robots in the order of the reversed ``who``
    reversed_out = make_streams(seeds, sizes).draw(who[::-1], draw_one)[0]
    starts = np.concatenate([[0], np.cumsum(sizes)])
    run = np.searchsorted(starts, who, side="right") - 1
    for g in range(len(sizes)):
        mine = run == g
        np.testing.assert_array_equal(reversed_out[::-1][mine], sorted_out[mine][::-1])


def test_interleaved_runs_get_their_numbers_in_place() -> None:
    streams = make_streams([1, 2], [3, 3])
    got = streams.draw(np.array([4, 0, 5, 1, 3]), draw_one)[0]
    a = np.random.default_rng(1).random(2)
    b = np.random.default_rng(2).random(3)
    np.testing.assert_array_equal(got, [b[0], a[0], b[1], a[1], b[2]])


def test_generators_advance_only_for_runs_that_draw() -> None:
    streams = make_streams([10, 11, 12], [2, 2, 2])
    streams.draw(np.array([0, 1, 5]), draw_one)  # runs 0 and 2 draw, run 1 does not
    ref = [np.random.default_rng(s) for s in (10, 11, 12)]
    ref[0].random(2)
    ref[2].random(1)
    for g, r in zip(streams.generators, ref, strict=True):
        assert g.random() == r.random()


def test_one_run_in_streams_equals_the_plain_generator() -> None:
    streams = make_streams([42], [8])
    plain = np.random.default_rng(42)
    for who in (np.arange(8), np.array([7, 2, 5]), np.array([], dtype=np.int64), np.array([3])):
        got = draw_per_run(streams, who, draw_mixed)
        want = draw_per_run(plain, who, draw_mixed)
        for g, w in zip(got, want, strict=True):
            np.testing.assert_array_equal(g, w)


def test_runs_without_robots_are_skipped() -> None:
    streams = make_streams([1, 2, 3, 4], [0, 2, 0, 1])
    got = streams.draw(np.array([0, 1, 2]), draw_one)[0]
    np.testing.assert_array_equal(got[:2], np.random.default_rng(2).random(2))
    assert got[2] == np.random.default_rng(4).random(1)[0]
    assert streams.generators[0].random() == np.random.default_rng(1).random()
    assert streams.generators[2].random() == np.random.default_rng(3).random()


def test_nobody_drawing_gives_empty_arrays_of_the_right_types() -> None:
    streams = make_streams([5, 6], [2, 3])
    got = streams.draw(np.array([], dtype=np.int64), draw_mixed)
    want = draw_mixed(np.random.default_rng(0), 0)
    assert len(got) == 4
    for g, w in zip(got, want, strict=True):
        assert g.shape == w.shape
        assert g.dtype == w.dtype
    assert got[3].shape == (0, 2)
    assert streams.generators[0].random() == np.random.default_rng(5).random()
    assert streams.generators[1].random() == np.random.default_rng(6).random()


def test_who_may_be_a_list() -> None:
    got = make_streams([3], [4]).draw([2, 0], draw_one)[0]
    np.testing.assert_array_equal(got, np.random.default_rng(3).random(2))


def test_starts_must_have_one_more_entry_than_generators() -> None:
    gens = [np.random.default_rng(0), np.random.default_rng(1)]
    with pytest.raises(ValueError, match="starts needs 3 entries, got 2"):
        RunStreams(gens, np.array([0, 4]))
    with pytest.raises(ValueError, match="starts needs 3 entries, got 4"):
        RunStreams(gens, np.array([0, 4, 8, 9]))


def test_streams_keep_the_generators_and_starts() -> None:
    gens = [np.random.default_rng(0), np.random.default_rng(1)]
    streams = RunStreams(tuple(gens), [0, 2, 5])
    assert streams.generators == gens
    assert streams.generators[0] is gens[0]
    assert streams.starts.dtype == np.int64
    np.testing.assert_array_equal(streams.starts, [0, 2, 5])


# --- draw_per_run with a plain generator -------------------------------------------------------------------


@given(st.integers(min_value=0, max_value=2**32 - 1), st.lists(st.integers(min_value=0, max_value=100), max_size=20))
def test_plain_generator_draws_directly_for_len_who(seed: int, who: list[int]) -> None:
    rng = np.random.default_rng(seed)
    got = draw_per_run(rng, np.asarray(who, dtype=np.int64), draw_mixed)
    want = draw_mixed(np.random.default_rng(seed), len(who))
    for g, w in zip(got, want, strict=True):
        np.testing.assert_array_equal(g, w)
    ref = np.random.default_rng(seed)
    draw_mixed(ref, len(who))
    assert rng.random() == ref.random()


def test_plain_generator_gets_the_callers_generator_and_count() -> None:
    rng = np.random.default_rng(0)
    seen = []

    def spy(generator: np.random.Generator, m: int) -> tuple[np.ndarray, ...]:
        seen.append((generator, m))
        return (np.arange(m),)

    out = draw_per_run(rng, np.array([9, 3, 7]), spy)
    assert seen == [(rng, 3)]
    np.testing.assert_array_equal(out[0], [0, 1, 2])


def test_streams_call_draw_once_per_drawing_run_in_block_order() -> None:
    streams = make_streams([0, 1, 2], [2, 2, 2])
    seen = []

    def spy(generator: np.random.Generator, m: int) -> tuple[np.ndarray, ...]:
        seen.append((streams.generators.index(generator), m))
        return (np.full(m, len(seen)),)

    out = draw_per_run(streams, np.array([5, 0, 4, 1]), spy)
    assert seen == [(0, 2), (2, 2)]
    np.testing.assert_array_equal(out[0], [2, 1, 2, 1])
