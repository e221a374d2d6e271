"""Fingerprints of the learning environments: observations, rewards and ends over whole episodes, bit for bit.

The digests were taken before the vectorised environment was made faster; a change that moves one bit of what a
learner sees or earns changes them. Like the golden fingerprints they hold with numpy at AVX2 at most (``make test``
sets ``NPY_DISABLE_CPU_FEATURES``; see the Makefile).
"""

from __future__ import annotations

import hashlib

import numpy as np
import pytest

pytest.importorskip("pettingzoo")
pytest.importorskip("gymnasium")

from amronet.env import deployment_env
from amronet.env.vector import VecRouterEnv


def _feed(h, value) -> None:
    a = np.ascontiguousarray(value)
    h.update(f"{a.dtype.str}{a.shape}".encode())
    h.update(a.tobytes())


def _feed_obs(h, obs: dict[str, np.ndarray]) -> None:
    for key in sorted(obs):
        h.update(key.encode())
        _feed(h, obs[key])


def _vector_digest(motion: str, actions: str, **options) -> str:
    env = VecRouterEnv(seeds=[1, 2, 3], max_steps=45, motion=motion, actions=actions, **options)
    rng = np.random.default_rng(7)
    h = hashlib.sha256()
    _feed_obs(h, env.reset())
    steps = 0
    while env.live.any():
        shape = env.live.shape
        if motion == "builtin":
            act = (rng.random(shape) < 0.03).astype(np.int64)
        elif actions == "discrete":
            act = np.stack([rng.integers(0, 5, shape), rng.random(shape) < 0.03], -1)
        else:
            act = np.stack([rng.uniform(-1, 1, shape), rng.uniform(0, 1, shape), rng.random(shape)], -1)
            act[..., 2] = act[..., 2] < 0.03
        obs, rewards, terminated, truncated, info = env.step(act)
        _feed_obs(h, obs)
        for value in (rewards, terminated, truncated, info["connected_coverage"]):
            _feed(h, value)
        steps += 1
    assert steps == 45  # (the runs reach the truncation: every path of a step is taken)
    return h.hexdigest()[:16]


@pytest.mark.parametrize(("motion", "actions", "options", "digest"), [
    ("policy", "discrete", {}, "8b0be1d31083fdbb"),
    ("policy", "continuous", {"patch": 7, "links": 3}, "1ffbdff5123a3816"),
    ("builtin", "discrete", {}, "171c15a4048846a8"),
])
def test_the_vectorised_router_environment_gives_the_same_bits(motion, actions, options, digest):
    assert _vector_digest(motion, actions, **options) == digest


def test_the_agent_environment_gives_the_same_bits():
    env = deployment_env(overrides={"agents.per_base": 2}, max_steps=40, patch=9, seed=1)
    rng = np.random.default_rng(3)
    obs, _ = env.reset(seed=5)
    h = hashlib.sha256()
    for name in sorted(obs):
        _feed_obs(h, obs[name])
    while env.agents:
        actions = {}
        for a in env.agents:
            act = np.array([rng.uniform(-1, 1), rng.uniform(0, 1), float(rng.random() < 0.05)])
            actions[a] = act
        obs, rewards, terminated, truncated, _ = env.step(actions)
        for name in sorted(obs):
            _feed_obs(h, obs[name])
            _feed(h, np.array([rewards[name], terminated[name], truncated[name]], dtype=float))
    assert h.hexdigest()[:16] == "a1a74249b093aa30"
