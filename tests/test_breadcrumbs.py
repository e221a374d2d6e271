"""``repair: retrace``'s breadcrumbs (:mod:`amronet.algorithms.agent_assisted.breadcrumbs`) as they were in Python.

The compiled kernel keeps the paths in per-agent buffers and adds the points of a whole stretch in one call; every
operation must leave the same points, parents, paths and tips, and return the same points, as the Python version
it replaced (:class:`_Reference`, kept here as it was).
"""

from __future__ import annotations

import math

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st
from numba import njit

import amronet.algorithms.agent_assisted.breadcrumbs as breadcrumbs
from amronet.algorithms.agent_assisted.breadcrumbs import Breadcrumbs
from amronet.sim.warmup import warmup_cases


class _Reference:
    """The Python breadcrumbs the kernel replaced (paths as arrays, appended point by point)."""

    def __init__(self, xy: np.ndarray, spacing: float, erase: float) -> None:
        self.spacing = spacing
        self.erase = erase
        self.xy = np.zeros((max(64, 4 * len(xy)), 2))
        self.parent = np.full(len(self.xy), -1, dtype=np.int64)
        self.count = 0
        self.paths = [np.array([self.add(p, -1)], dtype=np.int64) for p in np.asarray(xy, dtype=float)]
        self.tip = np.array([path[-1] for path in self.paths], dtype=np.int64)

    def _room(self, k: int) -> None:
        while self.count + k > len(self.xy):
            self.xy = np.concatenate([self.xy, np.zeros_like(self.xy)])
            self.parent = np.concatenate([self.parent, np.full(len(self.parent), -1, dtype=np.int64)])

    def add(self, p: np.ndarray, parent: int) -> int:
        self._room(1)
        k = self.count
        self.xy[k] = p
        self.parent[k] = parent
        self.count += 1
        return k

    def set_path(self, m: int, path: np.ndarray) -> None:
        self.paths[m] = path
        self.tip[m] = path[-1]

    def record(self, xy: np.ndarray, who: np.ndarray) -> None:
        tip = self.xy[self.tip]
        moved = who & (np.hypot(xy[:, 0] - tip[:, 0], xy[:, 1] - tip[:, 1]) >= self.spacing)
        for m in np.flatnonzero(moved):
            self.extend(m, xy[m])

    def replay(self, trail: np.ndarray) -> None:
        found = []
        for m in range(trail.shape[1]):
            tip = self.xy[self.tip[m]]
            s = 0
            while s < len(trail):
                way = trail[s:, m]
                hit = np.flatnonzero(np.hypot(way[:, 0] - tip[0], way[:, 1] - tip[1]) >= self.spacing)
                if not len(hit):
                    break
                s += int(hit[0])
                found.append((s, m))
                tip = trail[s, m]
                s += 1
        for s, m in sorted(found):
            self.extend(m, trail[s, m])

    def back(self, m: int, p: np.ndarray, reach: float) -> int:
        path = self.paths[m]
        k = len(path)
        while k > 1 and np.hypot(*(self.xy[path[k - 1]] - p)) <= reach:
            k -= 1
        self.set_path(m, path[:k])
        return -1 if k == 1 and np.hypot(*(self.xy[path[0]] - p)) <= reach else int(path[k - 1])

    def extend(self, m: int, p: np.ndarray) -> int:
        path = self.paths[m]
        d = np.hypot(*(self.xy[path] - p).T)
        close = np.flatnonzero(d < self.erase)
        if len(close):
            path = path[:close[0] + 1]
        k = self.add(p, int(path[-1]))
        self.set_path(m, np.append(path, k))
        return k


def _same(new: Breadcrumbs, old: _Reference) -> None:
    assert new.count == old.count
    np.testing.assert_array_equal(new.xy[:new.count], old.xy[:old.count])
    np.testing.assert_array_equal(new.parent[:new.count], old.parent[:old.count])
    np.testing.assert_array_equal(new.tip, old.tip)
    assert len(new.paths) == len(old.paths)
    for x, y in zip(new.paths, old.paths, strict=True):
        np.testing.assert_array_equal(x, y)


# positions on a lattice of a quarter of the spacing, the spacing and erasing radius whole multiples of it: many
# distances fall exactly on the spacing or the erasing radius (the comparisons' edges); or anywhere (rounding)
_SPACING, _ERASE = 0.5, 0.75


@st.composite
def _positions(draw: st.DrawFn, shape: tuple[int, ...]) -> np.ndarray:
    rng = np.random.default_rng(draw(st.integers(0, 2**32 - 1)))
    if draw(st.booleans()):
        return rng.integers(-6, 7, shape) * (0.25 * _SPACING)
    return rng.uniform(-1.5, 1.5, shape)


@st.composite
def _walk(draw: st.DrawFn, steps: int, agents: int) -> np.ndarray:
    """A trail ``(steps, agents, 2)``: random walks that wander back over their own way (loops that erase)."""
    rng = np.random.default_rng(draw(st.integers(0, 2**32 - 1)))
    scale = draw(st.sampled_from([0.1, 0.3, 0.6]))
    if draw(st.booleans()):
        return np.round(np.cumsum(rng.normal(0, scale, (steps, agents, 2)), axis=0) / (0.25 * _SPACING)) * (
            0.25 * _SPACING)
    return np.cumsum(rng.normal(0, scale, (steps, agents, 2)), axis=0)


@st.composite
def _operations(draw: st.DrawFn) -> tuple[int, list[tuple]]:
    agents = draw(st.integers(1, 4))
    ops: list[tuple] = []
    for _ in range(draw(st.integers(1, 25))):
        kind = draw(st.sampled_from(["record", "replay", "replay", "extend", "back", "drop tip"]))
        m = draw(st.integers(0, agents - 1))
        if kind == "record":
            who = np.array(draw(st.lists(st.booleans(), min_size=agents, max_size=agents)))
            ops.append((kind, draw(_positions((agents, 2))), who))
        elif kind == "replay":
            ops.append((kind, draw(_walk(draw(st.integers(0, 60)), agents))))
        elif kind == "extend":
            ops.append((kind, m, draw(_positions((2,)))))
        elif kind == "back":
            ops.append((kind, m, draw(_positions((2,))), draw(st.sampled_from([0.25, 0.5, 1.0]))))
        else:
            ops.append((kind, m))
    return agents, ops


@settings(max_examples=300, deadline=None)
@given(_operations(), st.data())
def test_breadcrumbs_match_the_python_version(case, data):
    """Any sequence of records, stretch replays, hand-overs (extend), backing up and skipped points: the same books."""
    agents, ops = case
    start = data.draw(_positions((agents, 2)))
    new, old = Breadcrumbs(start, _SPACING, _ERASE), _Reference(start, _SPACING, _ERASE)
    _same(new, old)
    for op in ops:
        if op[0] == "record":
            new.record(op[1], op[2])
            old.record(op[1], op[2])
        elif op[0] == "replay":
            new.replay(op[1])
            old.replay(op[1])
        elif op[0] == "extend":
            assert new.extend(op[1], op[2]) == old.extend(op[1], op[2])
        elif op[0] == "back":
            assert new.back(op[1], op[2], op[3]) == old.back(op[1], op[2], op[3])
        elif len(old.paths[op[1]]) > 1:  # a skipped point (Retracer.steer_agents)
            new.set_path(op[1], new.paths[op[1]][:-1])
            old.set_path(op[1], old.paths[op[1]][:-1])
        _same(new, old)


@settings(max_examples=40, deadline=None)
@given(st.integers(0, 2**32 - 1), st.integers(1, 3))
def test_long_stretches_outgrow_the_buffers(seed, agents):
    """Hundreds of points, paths hundreds long (the buffers grow): the same books."""
    rng = np.random.default_rng(seed)
    start = rng.uniform(0, 5, (agents, 2))
    trail = start + np.cumsum(rng.normal(0.2, 0.3, (400, agents, 2)), axis=0)
    new, old = Breadcrumbs(start, 0.3, 0.4), _Reference(start, 0.3, 0.4)
    for part in np.array_split(trail, 3):
        new.replay(part)
        old.replay(part)
    assert max(len(p) for p in old.paths) > 100
    _same(new, old)


@njit(cache=False)
def _compiled_hypot(x: np.ndarray, y: np.ndarray) -> np.ndarray:  # what record_points computes
    out = np.empty_like(x)
    for i in range(len(x)):
        out[i] = math.hypot(x[i], y[i])
    return out


def test_compiled_hypot_is_numpys_bit_for_bit():
    """The kernel's distances are numpy's: the same comparisons with the spacing and the erasing radius."""
    rng = np.random.default_rng(3)
    x = np.concatenate([rng.uniform(-40, 40, 200_000), rng.normal(0, 1e-3, 50_000),
                        rng.integers(-40, 41, 50_000) * 0.125, [0.0, -0.0, 5e-324, 1e300, 3.0, 0.3]])
    y = np.concatenate([rng.uniform(-40, 40, 200_000), rng.normal(0, 1e-3, 50_000),
                        rng.integers(-40, 41, 50_000) * 0.125, [0.0, 1.0, 5e-324, 1e300, 4.0, 0.4]])
    np.testing.assert_array_equal(_compiled_hypot(x, y).view(np.int64), np.hypot(x, y).view(np.int64))


def test_the_warm_up_compiles_the_kernel(monkeypatch):
    """``amronet compile`` reaches the kernel (a retrace run's first step records the agents' odometry)."""
    calls = []

    def spy(*args):
        calls.append(args[6].shape)
        return record_points(*args)

    record_points = breadcrumbs.record_points
    monkeypatch.setattr(breadcrumbs, "record_points", spy)
    next(case for case in warmup_cases() if case.label == "faults and retrace").run()
    assert calls
