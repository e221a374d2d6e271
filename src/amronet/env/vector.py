"""Many seeds at once: the environments with arrays in and out, for training loops that batch their policies.

:class:`VecRouterEnv` steps the self-spreading runs of ``G`` seeds in one
:class:`~amronet.sim.batch.BatchSimulation` (one set of arrays, one neighbour table, one controller; every run bit for
bit the run of its seed alone). :class:`VecDeploymentEnv` steps ``G`` agent-assisted environments in turn (agents put
routers down mid-step, which a batch's blocks of robots cannot hold). Both take actions ``(G, A, ...)`` and return
observations ``{key: (G, A, ...)}``, rewards, terminations and truncations ``(G, A)``; an agent that has finished
gets zeros and ``False`` and its actions are not read. A run stays finished until :meth:`reset`.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from amronet.env.actions import action_space, decode_array
from amronet.env.agents import DeploymentEnv
from amronet.env.config import EnvConfig, RewardWeights
from amronet.env.errors import EnvError
from amronet.env.router_core import RouterCore
from amronet.env.scenarios import EnvScenario, ScenarioRef
from amronet.sim.batch import BatchSimulation, batchable
from amronet.sim.loop import check_seed

__all__ = ["VecDeploymentEnv", "VecRouterEnv"]

Step = tuple[dict[str, np.ndarray], np.ndarray, np.ndarray, np.ndarray, dict[str, Any]]


def _seeds(seeds: Sequence[int]) -> list[int]:
    if len(seeds) == 0:
        raise EnvError("seeds", "give at least one seed")
    return [check_seed(s) for s in seeds]


def _config(max_steps: int | None, motion: str, actions: str, reward: RewardWeights | None,
            options: dict[str, Any]) -> EnvConfig:
    return EnvConfig(max_steps=max_steps, motion=motion, actions=actions,  # type: ignore[arg-type]
                     reward=reward if reward is not None else RewardWeights(), **options)


class VecRouterEnv:
    """The router environment over ``len(seeds)`` seeds in one batch (arguments as :func:`amronet.env.router_env`).

    Raises:
        EnvError: The scenario cannot be batched (a radio that draws random numbers, faults), or no seed.
    """

    def __init__(self, scenario: ScenarioRef = "self-spreading-obstacles-6x6", seeds: Sequence[int] = (1,),
                 overrides: dict[str, Any] | None = None, *, max_steps: int | None = None, motion: str = "policy",
                 actions: str = "continuous", reward: RewardWeights | None = None, **options: Any) -> None:
        self.config = _config(max_steps, motion, actions, reward, options)
        self.setup = EnvScenario(scenario, overrides, "self-spreading", self.config)
        if not batchable(self.setup.run):
            raise EnvError("scenario", "its runs cannot share one batch (a radio with shadowing or packet loss, or "
                           "faults); use router_env one seed at a time")
        self.action_space = action_space(self.config)
        self.reset(seeds)

    def reset(self, seeds: Sequence[int] | None = None) -> dict[str, np.ndarray]:
        """Start every run again (with new seeds when given); the observations ``{key: (G, R, ...)}``."""
        self.seeds = _seeds(self.seeds if seeds is None else list(seeds))
        self.loop = BatchSimulation(self.setup.run, self.seeds)
        self.core = RouterCore(self.loop, self.config, self.setup.max_steps)
        self.observation_space = self.core.observer.space()
        return self._obs()

    @property
    def live(self) -> np.ndarray:
        """Which routers act at the next step ``(G, R)``."""
        return self.core.live

    def _obs(self) -> dict[str, np.ndarray]:
        g, r = self.core.ids.shape
        return {k: v.reshape(g, r, *v.shape[1:]) for k, v in self.core.observe().items()}

    def step(self, actions: np.ndarray) -> Step:
        """One step of every run: ``(observations, rewards, terminated, truncated, info)``.

        Raises:
            EnvError: Every run has finished, the array has the wrong shape, or a live entry is outside the space.
        """
        if not self.core.live.any():
            raise EnvError("step", "every run has finished; call reset() first")
        turn, speed, wish = decode_array(self.config, self.action_space, actions, self.core.live)
        rewards, terminated, truncated, _ = self.core.step(turn, speed, wish)
        return self._obs(), rewards, terminated, truncated, {"connected_coverage": self.core.coverage.copy()}


class VecDeploymentEnv:
    """The agent-assisted environment over ``len(seeds)`` seeds, stepped in turn.

    Arguments as :func:`amronet.env.deployment_env`'s.
    """

    def __init__(self, scenario: ScenarioRef = "agent-assisted-office", seeds: Sequence[int] = (1,),
                 overrides: dict[str, Any] | None = None, *, max_steps: int | None = None, motion: str = "policy",
                 actions: str = "continuous", reward: RewardWeights | None = None, **options: Any) -> None:
        self.config = _config(max_steps, motion, actions, reward, options)
        setup = EnvScenario(scenario, overrides, "agent-assisted", self.config)
        self.seeds = _seeds(seeds)
        self.envs = [DeploymentEnv(setup, self.config) for _ in self.seeds]
        self.action_space = action_space(self.config)
        first = self.envs[0]
        self.observation_space = first.observation_space(first.possible_agents[0])
        self.reset()

    def reset(self, seeds: Sequence[int] | None = None) -> dict[str, np.ndarray]:
        """Start every run again (with new seeds when given); the observations ``{key: (G, A, ...)}``."""
        if seeds is not None:
            seeds = _seeds(seeds)
            if len(seeds) != len(self.envs):
                raise EnvError("seeds", f"give {len(self.envs)} seeds, one per run")
            self.seeds = seeds
        obs = [env.reset(seed=seed)[0] for env, seed in zip(self.envs, self.seeds, strict=True)]
        self.live = np.ones((len(self.envs), len(self.envs[0].possible_agents)), dtype=bool)
        return self._stack(obs)

    def _stack(self, obs: list[dict[str, dict[str, np.ndarray]]]) -> dict[str, np.ndarray]:
        names = self.envs[0].possible_agents
        keys = next(iter(obs[0].values())).keys()
        return {k: np.stack([np.stack([o[a][k] for a in names]) for o in obs]) for k in keys}

    def step(self, actions: np.ndarray) -> Step:
        """One step of every run that has not finished: ``(observations, rewards, terminated, truncated, info)``.

        Raises:
            EnvError: Every run has finished, the array has the wrong shape, or a live entry is outside the space.
        """
        if not self.live.any():
            raise EnvError("step", "every run has finished; call reset() first")
        decode_array(self.config, self.action_space, actions, self.live)  # (the checks, for every run at once)
        g, n = self.live.shape
        rewards, terms, truncs = np.zeros((g, n)), np.zeros((g, n), bool), np.zeros((g, n), bool)
        obs = []
        for k, env in enumerate(self.envs):
            names = env.possible_agents
            if not self.live[k].any():
                obs.append(self._last[k])
                continue
            act = {a: actions[k][m] for m, a in enumerate(names)}
            o, r, te, tr, _ = env.step(act)
            obs.append(o)
            rewards[k] = [r[a] for a in names]
            terms[k] = [te[a] for a in names]
            truncs[k] = [tr[a] for a in names]
        self._last = obs
        self.live &= ~(terms | truncs)
        return self._stack(obs), rewards, terms, truncs, {}
