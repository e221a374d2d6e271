"""Compiled draws through the bit generators' C interface: numpy's numbers, bit for bit, and the state left behind."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from amronet.engine.bitgen import addresses, draw_normal_uniform
from amronet.engine.motion import random_walk, random_walk_drawing
from amronet.engine.sensing import beam_angles
from amronet.engine.streams import RunStreams, compiled_streams

BIT_GENERATORS = (np.random.PCG64, np.random.PCG64DXSM, np.random.Philox, np.random.SFC64, np.random.MT19937)


@settings(max_examples=60, deadline=None)
@given(sizes=st.lists(st.integers(0, 40), min_size=1, max_size=6), seed=st.integers(0, 2**32 - 1),
       share=st.floats(0.0, 1.0))
def test_a_batch_draws_what_its_runs_streams_draw(sizes, seed, share):
    # each run's walkers get standard normals, then uniforms, from the run's own generator, as RunStreams draws them
    starts = np.concatenate([[0], np.cumsum(sizes)]).astype(np.int64)
    who = np.flatnonzero(np.random.default_rng(seed).random(starts[-1]) < share).astype(np.int64)
    ours = [np.random.default_rng([seed, g]) for g in range(len(sizes))]
    theirs = [np.random.default_rng([seed, g]) for g in range(len(sizes))]
    normal, uniform = np.empty(len(who)), np.empty(len(who))
    assert draw_normal_uniform(addresses(ours), starts, who, normal, uniform)
    want_normal, want_uniform = RunStreams(theirs, starts).normal_then_uniform(who)
    np.testing.assert_array_equal(normal, want_normal)
    np.testing.assert_array_equal(uniform, want_uniform)
    for a, b in zip(ours, theirs, strict=True):  # every generator left where numpy's draws leave it
        assert a.bit_generator.state == b.bit_generator.state


@pytest.mark.parametrize("kind", BIT_GENERATORS, ids=lambda k: k.__name__)
def test_many_draws_equal_numpys_including_the_ziggurats_tails(kind):
    # 200 000 normals reach the ziggurat's rare branches (the wedges and, about once in 3000 draws, the tail)
    n = 200_000
    ours, theirs = np.random.Generator(kind(7)), np.random.Generator(kind(7))
    normal, uniform = np.empty(n), np.empty(n)
    bitgens, starts = compiled_streams(ours, n)
    assert draw_normal_uniform(bitgens, starts, np.arange(n), normal, uniform)
    np.testing.assert_array_equal(normal, theirs.standard_normal(n))
    np.testing.assert_array_equal(uniform, theirs.random(n))
    assert np.abs(normal).max() > 3.6  # some beyond the ziggurat's base strip (r = 3.654...)
    assert ours.random() == theirs.random()


def test_refuses_robots_out_of_order_or_outside_the_runs_and_draws_nothing():
    g = np.random.default_rng(3)
    before = g.bit_generator.state
    starts = np.array([0, 5, 10], dtype=np.int64)
    out = np.empty(3)
    for who in ([4, 2, 7], [1, 1, 2], [3, 6, 10], [-1, 2, 3]):
        assert not draw_normal_uniform(addresses([g, g]), starts, np.array(who, dtype=np.int64), out, out.copy())
    assert g.bit_generator.state == before


@settings(max_examples=60, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), m=st.integers(1, 6))
def test_the_compiled_random_walk_draws_and_turns_as_random_walk(seed, m):
    # the robots without a plan walk: their normals, then their uniforms, from the generator in place (the agents'
    # idle walk in a quiet stretch, amronet.algorithms.agent_assisted.stretch_kernels)
    setup = np.random.default_rng(seed)
    n, beams, reach = m + 3, 16, 0.6
    who = setup.permutation(n)[:m].astype(np.int64)
    planned = setup.random(m) < 0.4
    scans = np.minimum(setup.uniform(0.1, 3.0, (m, beams)), reach)
    refused = setup.random(m) < 0.3
    heading = setup.uniform(-np.pi, np.pi, n)
    ours, theirs = np.random.default_rng([seed, 1]), np.random.default_rng([seed, 1])
    got, want = heading.copy(), heading.copy()
    walked = random_walk_drawing(int(addresses([ours])[0]), got, who, planned, scans, beam_angles(beams), reach,
                                 refused, 0.5 * np.sqrt(0.1), np.empty(m), np.empty(m))
    idle = ~planned
    random_walk(want, who[idle], scans[idle], reach, refused[idle], theirs, 0.5 * np.sqrt(0.1))
    assert walked == np.count_nonzero(idle)
    np.testing.assert_array_equal(got, want)
    assert ours.bit_generator.state == theirs.bit_generator.state
