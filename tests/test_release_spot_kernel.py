"""The compiled release-spot search gives the spots of the NumPy form it replaced, bit for bit.

The NumPy form is kept here as the reference (:func:`_reference_spot`, :func:`_segments_clear`). Its matrix product
``rel @ seg.T`` goes through OpenBLAS, which rounds a 2-term dot product with one fused multiply-add: the kernel
does the same (:func:`~amronet.algorithms.agent_assisted.release_kernels.dot2`), checked here on every shape.
"""

from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st
from numba import njit

from amronet.algorithms.agent_assisted.release_kernels import dot2, segment_gap
from amronet.algorithms.agent_assisted.releases import release_spot


def _segments_clear(p, ends, r, xy, radius):
    """The NumPy form: which segments ``p -> ends[m]`` a body of radius ``r`` can be carried along."""
    seg = ends - p
    length2 = np.maximum(np.einsum("ij,ij->i", seg, seg), 1e-300)
    rel = xy - p
    t = np.clip((rel @ seg.T) / length2[None, :], 0.0, 1.0)
    closest = p[None, None, :] + t[:, :, None] * seg[None, :, :]
    d = np.linalg.norm(xy[:, None, :] - closest, axis=2)
    return (d >= r + radius[:, None]).all(axis=0)


def _reference_spot(p, ref, gap, step, r, within, path_clear, xy, radius, agent):
    """The NumPy form of the release-spot search (``Releasing._release_spot`` before it was compiled)."""
    base = np.arctan2(ref[1] - p[1], ref[0] - p[0])
    others = np.delete(np.arange(len(xy)), agent)
    turns = np.array([0, 1, -1, 2, -2, 3, -3, 4, -4, 5, -5, 6]) * (np.pi / 6)
    cand = p + gap * np.stack([np.cos(base + turns), np.sin(base + turns)], axis=1)
    ok = np.linalg.norm(cand - ref, axis=1) <= within
    ok &= path_clear(np.repeat(p[None], len(cand), axis=0), cand, np.full(len(cand), r))
    if len(others):
        d = np.linalg.norm(cand[:, None, :] - xy[None, others, :], axis=2)
        ok &= (d >= r + radius[others][None, :]).all(axis=1)
    hit = np.flatnonzero(ok)
    if len(hit):
        return cand[hit[0]]
    turns = np.concatenate([[0.0], np.repeat(np.arange(1, 12), 2) * np.array([1.0, -1.0] * 11), [12.0]]) * (
        np.pi / 12)
    dirs = np.stack([np.cos(base + turns), np.sin(base + turns)], axis=1)
    cand = np.concatenate([p + (gap + k * step) * dirs for k in (1, 2)])
    ok = np.linalg.norm(cand - ref, axis=1) <= within
    ok[ok] &= path_clear(np.repeat(p[None], int(ok.sum()), axis=0), cand[ok], np.full(int(ok.sum()), r))
    if len(others) and ok.any():
        ok[ok] &= _segments_clear(p, cand[ok], r, xy[others], radius[others])
    hit = np.flatnonzero(ok)
    return cand[hit[0]] if len(hit) else None


@njit
def _dots(rel, seg):
    n, m = rel.shape[0], seg.shape[0]
    out = np.empty((n, m))
    for j in range(n):
        for k in range(m):
            out[j, k] = dot2(rel[j, 0], rel[j, 1], seg[k, 0], seg[k, 1], (n == 1) != (m == 1))
    return out


@njit
def _gaps(p, ends, xy):
    n, m = xy.shape[0], ends.shape[0]
    out = np.empty((n, m))
    for k in range(m):
        sx = ends[k, 0] - p[0]
        sy = ends[k, 1] - p[1]
        length2 = max(sx * sx + sy * sy, 1e-300)
        for j in range(n):
            out[j, k] = segment_gap(p[0], p[1], sx, sy, length2, xy[j, 0], xy[j, 1], (n == 1) != (m == 1))
    return out


_coord = st.floats(-40.0, 40.0, allow_nan=False, allow_subnormal=False)


def _points(n_min, n_max):
    return st.integers(n_min, n_max).flatmap(
        lambda n: st.lists(st.tuples(_coord, _coord), min_size=n, max_size=n).map(lambda v: np.array(v, float)))


@settings(max_examples=300, deadline=None)
@given(rel=_points(1, 12), seg=_points(1, 12), seed=st.integers(0, 2**32 - 1))
def test_dot2_rounds_as_the_matrix_product(rel, seg, seed):
    jitter = np.random.default_rng(seed)  # values with many bits, so every rounding shows
    rel = rel + jitter.normal(size=rel.shape) * 1e-3
    seg = seg + jitter.normal(size=seg.shape) * 1e-3
    np.testing.assert_array_equal(_dots(rel, seg), rel @ seg.T, strict=True)


def _reference_gaps(p, ends, xy):
    seg = ends - p
    length2 = np.maximum(np.einsum("ij,ij->i", seg, seg), 1e-300)
    t = np.clip(((xy - p) @ seg.T) / length2[None, :], 0.0, 1.0)
    closest = p[None, None, :] + t[:, :, None] * seg[None, :, :]
    return np.linalg.norm(xy[:, None, :] - closest, axis=2)


@settings(max_examples=300, deadline=None)
@given(p=_points(1, 1), ends=_points(1, 10), xy=_points(1, 12), seed=st.integers(0, 2**32 - 1))
def test_segment_gaps_are_the_numpy_forms(p, ends, xy, seed):
    jitter = np.random.default_rng(seed)
    p, ends, xy = (a + jitter.normal(size=a.shape) * 1e-3 for a in (p[0], ends, xy))
    np.testing.assert_array_equal(_gaps(p, ends, xy), _reference_gaps(p, ends, xy), strict=True)


def _walls(start, end, radius):
    """A pure stand-in for the agent's hand: a wall along x = 0.3 (plus the radius) that no straight line crosses."""
    del radius
    return ~((start[:, 0] < 0.3) & (end[:, 0] >= 0.3))


def _scene(bodies, grid):
    """Positions around an agent at the origin: on a coarse grid (ties on the distance limits) or jittered."""
    xy = np.array(bodies, float)
    if grid:
        return np.round(xy * 8.0) / 8.0
    return xy


@settings(max_examples=400, deadline=None)
@given(bodies=st.lists(st.tuples(st.floats(-1.5, 1.5), st.floats(-1.5, 1.5)), min_size=2, max_size=14),
       grid=st.booleans(), near=st.booleans(), walls=st.booleans(), ref_at=st.integers(0, 100),
       radii=st.sampled_from([(0.15, 0.1, 0.05), (0.2, 0.125, 0.0), (0.1, 0.1, 0.02)]))
def test_release_spot_is_the_numpy_forms(bodies, grid, near, walls, ref_at, radii):
    xy = _scene(bodies, grid)
    agent = 0
    ref = 1 + ref_at % (len(xy) - 1)
    agent_r, r, release_gap = radii
    radius = np.full(len(xy), r)
    radius[agent] = agent_r
    gap = radius[agent] + r + release_gap
    step = 2.0 * r + release_gap
    within = 1.0 if near else np.inf
    clear = _walls if walls else (lambda start, end, rad: np.ones(len(start), dtype=bool))
    args = (xy[agent], xy[ref], gap, step, r, within, clear, xy, radius, agent)
    new, old = release_spot(*args), _reference_spot(*args)
    assert (new is None) == (old is None)
    if old is not None:
        np.testing.assert_array_equal(new, old, strict=True)


def test_crowded_agents_find_the_farther_rings_spot_and_none_when_full():
    """The agent's ring taken: the spot is on a farther ring (its line clear of bodies); boxed in: no spot."""
    xy = np.array([[0.0, 0.0], [-1.0, 0.0], *[[0.35 * np.cos(a), 0.35 * np.sin(a)] for a in np.arange(12) * np.pi / 6]])
    radius = np.full(len(xy), 0.03)
    args = (xy[0], xy[1], 0.35, 0.25, 0.03, np.inf, lambda s, e, rad: np.ones(len(s), bool), xy, radius, 0)
    spot, old = release_spot(*args), _reference_spot(*args)
    np.testing.assert_array_equal(spot, old, strict=True)
    np.testing.assert_allclose(spot, 0.6 * np.array([np.cos(np.pi * 13 / 12), np.sin(np.pi * 13 / 12)]))
    ring = np.array([[r * np.cos(a), r * np.sin(a)] for r in (0.6, 0.85) for a in np.arange(24) * np.pi / 12])
    boxed = np.concatenate([xy, ring])
    radius = np.full(len(boxed), 0.1)
    args = (boxed[0], boxed[1], 0.35, 0.25, 0.03, np.inf, lambda s, e, rad: np.ones(len(s), bool), boxed, radius, 0)
    assert release_spot(*args) is None and _reference_spot(*args) is None


def test_a_reference_out_of_reach_leaves_no_spot_and_the_hand_is_not_asked():
    """Farther than ``within`` beyond the farthest ring: no spot, found without a look at the walls."""
    asked = []

    def hand(start, end, radius):
        asked.append(len(start))
        return np.ones(len(start), dtype=bool)

    xy = np.array([[10.0, 20.0], [10.0 + 3.0 + 0.35 + 2 * 0.25 + 1e-6, 20.0]])
    radius = np.full(2, 0.03)
    assert release_spot(xy[0], xy[1], 0.35, 0.25, 0.03, 3.0, hand, xy, radius, 0) is None
    assert asked == []
    xy[1, 0] -= 2e-6  # just in reach: the search runs and finds the farthest ring's spot toward the reference
    spot = release_spot(xy[0], xy[1], 0.35, 0.25, 0.03, 3.0, hand, xy, radius, 0)
    assert asked and spot is not None
    np.testing.assert_array_equal(spot, _reference_spot(xy[0], xy[1], 0.35, 0.25, 0.03, 3.0, hand, xy, radius, 0))


@settings(max_examples=300, deadline=None)
@given(angle=st.floats(-np.pi, np.pi), off=st.floats(-1e-6, 1e-6), within=st.floats(0.5, 30.0),
       at=st.tuples(st.floats(-500.0, 500.0), st.floats(-500.0, 500.0)))
def test_spots_near_the_limit_of_reach_are_the_numpy_forms(angle, off, within, at):
    """References at about ``within`` beyond the farthest ring: the same answer as the full NumPy search."""
    gap, step, r = 0.35, 0.25, 0.03
    d = within + gap + 2.0 * step + off
    p = np.array(at)
    xy = np.array([p, p + d * np.array([np.cos(angle), np.sin(angle)])])
    radius = np.full(2, r)
    args = (xy[0], xy[1], gap, step, r, within, lambda s, e, rad: np.ones(len(s), bool), xy, radius, 0)
    new, old = release_spot(*args), _reference_spot(*args)
    assert (new is None) == (old is None)
    if old is not None:
        np.testing.assert_array_equal(new, old, strict=True)
