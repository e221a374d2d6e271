"""The self-spreading environment: the routers are the agents; each walks or settles.

A PettingZoo :class:`~pettingzoo.utils.env.ParallelEnv` over one self-spreading run (:mod:`amronet.env.router_core`
says what a router observes, acts on and is rewarded for). The environment hands each router's action to the
``external`` walk and stop rule (:mod:`amronet.algorithms.self_spreading.external`) and steps the loop; reference
tracking, triangles, the move with its collision checks, the radio and coverage run unchanged. Routers that settle
leave ``env.agents``; the episode ends when none is left.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from amronet.env.actions import action_space, decode
from amronet.env.config import EnvConfig
from amronet.env.errors import EnvError
from amronet.env.observe import split
from amronet.env.router_core import ROUTER_FLAGS, RouterCore
from amronet.env.scenarios import EnvScenario
from amronet.env.spaces_of import SharedSpaces
from amronet.sim.loop import check_seed
from amronet.sim.simulation import Simulation

__all__ = ["RouterEnv"]


class RouterEnv(SharedSpaces):
    """Routers that spread themselves (see the module docstring).

    Args:
        scenario: The scenario made ready (:class:`~amronet.env.scenarios.EnvScenario`, self-spreading).
        config: The environment's configuration.
        seed: Seed of the episodes reset without one.
    """

    metadata = {"name": "amronet_routers_v0", "render_modes": []}  # noqa: RUF012 - PettingZoo's class attribute
    flags = ROUTER_FLAGS
    """The names of the observation's ``flags``."""

    def __init__(self, scenario: EnvScenario, config: EnvConfig, seed: int | None = None) -> None:
        self.setup = scenario
        self.config = config
        self.max_steps = scenario.max_steps
        self.possible_agents = [f"router_{k}" for k in range(scenario.run.routers.count)]
        self.agents: list[str] = []
        self._seeds = np.random.default_rng(seed)
        self._act_space = action_space(config)
        self.core: RouterCore | None = None
        self.reset(seed=int(self._seeds.integers(2**31)))  # the spaces' bounds need a built run
        assert self.core is not None
        self._obs_space = self.core.observer.space()
        self.agents = []

    def reset(self, seed: int | None = None, options: dict[str, Any] | None = None
              ) -> tuple[dict[str, dict[str, np.ndarray]], dict[str, dict[str, Any]]]:
        """Start an episode: a fresh run of the scenario with ``seed`` (drawn from the environment's when ``None``)."""
        seed = int(self._seeds.integers(2**31)) if seed is None else check_seed(seed)
        self.seed = seed
        self.sim = Simulation(self.setup.run, seed)
        self.core = RouterCore(self.sim, self.config, self.max_steps)
        self.core.observer.reset()
        live = self.core.live[0]
        self.agents = [a for a, on in zip(self.possible_agents, live, strict=True) if on]
        obs = split(self.core.observe(), self.possible_agents)
        return {a: obs[a] for a in self.agents}, {a: {} for a in self.agents}

    def step(self, actions: dict[str, Any]) -> tuple[dict, dict, dict, dict, dict]:
        """Act once: observations, rewards, terminations, truncations and infos of the routers that acted.

        Raises:
            EnvError: The episode has ended, or an action is missing, unknown or outside its space.
        """
        core = self.core
        if not self.agents or core is None:
            raise EnvError("step", "the episode has ended; call reset() first")
        names = self.agents
        turn, speed, wish = decode(self.config, self._act_space, actions, names)
        index = {a: k for k, a in enumerate(self.possible_agents)}
        rows = np.array([index[a] for a in names])
        full = [np.zeros(len(self.possible_agents)) for _ in range(2)] + [np.zeros(len(self.possible_agents), bool)]
        for arr, values in zip(full, (turn, speed, wish), strict=True):
            arr[rows] = values
        rewards, terminated, truncated, _ = core.step(full[0][None], full[1][None], full[2][None])
        obs = split(core.observe(), self.possible_agents)
        info = {"connected_coverage": float(core.coverage[0]), "t": self.sim.t}
        out = ({a: obs[a] for a in names}, {a: float(rewards[0, index[a]]) for a in names},
               {a: bool(terminated[0, index[a]]) for a in names}, {a: bool(truncated[0, index[a]]) for a in names},
               {a: dict(info) for a in names})
        self.agents = [a for a in names if core.live[0, index[a]]]
        return out

    def render(self) -> None:
        """Nothing to render here: record a run with ``amronet run --record`` and replay it."""

    def close(self) -> None:  # noqa: D102
        self.core = None
