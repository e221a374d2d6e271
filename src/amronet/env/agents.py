"""The agent-assisted environment: the scenario's exploring agents learn when (and where) to drop routers.

A PettingZoo :class:`~pettingzoo.utils.env.ParallelEnv` over one :class:`~amronet.sim.simulation.Simulation` stepped
one step at a time. Each step every agent acts (:mod:`amronet.env.actions`); the environment hands the actions to the
``external`` explorer and drop rule of agent-assisted deployment
(:mod:`amronet.algorithms.agent_assisted.explorers.external`, :mod:`amronet.algorithms.agent_assisted.drops.external`)
and steps the loop: sensing, reference tracking, releasing routers where the controller puts them, triangles,
tethering, motion with its collision checks, the radio and coverage run unchanged.

Reward of agent ``a`` after a step (weights :class:`~amronet.env.config.RewardWeights`)::

    coverage x (connected coverage gained this step)      shared by the team
  - cut_off  x dt                                          if a has no path to a base station after the step
  - router   x (routers a put down this step)

Terminated: every agent, when the coverage target is reached (the scenario's ``sim.coverage_target``, 0.99 when not
set) or no agent carries a router any more (a finite ``agents.routers_carried``). Truncated: every agent, at
``max_steps``.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from gymnasium import spaces

from amronet.engine.network import agents_connected
from amronet.env.actions import action_space, decode
from amronet.env.config import EnvConfig
from amronet.env.errors import EnvError
from amronet.env.observe import Observer, split
from amronet.env.scenarios import EnvScenario
from amronet.env.spaces_of import SharedSpaces
from amronet.sim.loop import check_seed
from amronet.sim.simulation import Simulation

__all__ = ["AGENT_FLAGS", "DeploymentEnv"]

AGENT_FLAGS = ("connected", "dropped", "carries")
"""An agent's flags: it has a path to a base station; it put a reference router down in the last step; it carries
a router now."""


class DeploymentEnv(SharedSpaces):
    """Agents that explore and drop routers (see the module docstring).

    Args:
        scenario: The scenario made ready (:class:`~amronet.env.scenarios.EnvScenario`, agent-assisted).
        config: The environment's configuration.
        seed: Seed of the episodes reset without one (each such reset draws its seed from it).
    """

    metadata = {"name": "amronet_deployment_v0", "render_modes": []}  # noqa: RUF012 - PettingZoo's class attribute
    flags = AGENT_FLAGS
    """The names of the observation's ``flags``."""

    def __init__(self, scenario: EnvScenario, config: EnvConfig, seed: int | None = None) -> None:
        self.setup = scenario
        self.config = config
        self.max_steps = scenario.max_steps
        sc = scenario.run
        n_agents = sc.agents.per_base * len(sc.base_stations)
        self.possible_agents = [f"agent_{m}" for m in range(n_agents)]
        self.agents: list[str] = []
        self._seeds = np.random.default_rng(seed)
        self.sim: Simulation | None = None
        self._observer: Observer | None = None
        self._obs_space: spaces.Dict | None = None
        self._act_space = action_space(config)
        self.reset(seed=int(self._seeds.integers(2**31)))  # the spaces' bounds need a built run
        self.agents = []

    # -- the episode --------------------------------------------------------------------------------------------
    def reset(self, seed: int | None = None, options: dict[str, Any] | None = None
              ) -> tuple[dict[str, dict[str, np.ndarray]], dict[str, dict[str, Any]]]:
        """Start an episode: a fresh run of the scenario with ``seed`` (drawn from the environment's when ``None``)."""
        seed = int(self._seeds.integers(2**31)) if seed is None else check_seed(seed)
        self.seed = seed
        sim = self.sim = Simulation(self.setup.run, seed)
        ctl = sim.controller
        sw = sim.swarm
        self._ids = np.asarray(ctl.agents, dtype=np.int64)
        self._start = sw.xy[self._ids].copy()
        self._carried = sim.scenario.agents.routers_carried
        model = sw.models[int(sw.model[self._ids[0]])]
        if self._observer is None:
            self._observer = Observer(sim.world.omap, model.sensor_beams, model.sensor_range, sim.medium.reach,
                                      sim.medium.budget.threshold_dbm, AGENT_FLAGS, True, self.config,
                                      len(self._ids))
            self._obs_space = self._observer.space()
        self._observer.reset()
        self.agents = list(self.possible_agents)
        self.steps = 0
        self._connected_coverage = sim.metrics().connected_coverage
        obs = self._observe()
        return obs, {a: {} for a in self.agents}

    def _linked(self) -> np.ndarray:
        sim = self.sim
        assert sim is not None
        return agents_connected(sim.table, self._ids, sim.books.bases, sim.swarm.relaying)

    def _observe(self) -> dict[str, dict[str, np.ndarray]]:
        sim, obs = self.sim, self._observer
        assert sim is not None and obs is not None
        ctl, sw = sim.controller, sim.swarm
        left = ctl.left[self._ids]
        flags = np.stack([self._linked(), ctl.drop_rule.last_dropped, left >= 1], axis=1)
        stock = np.ones(len(left)) if self._carried is None else left / max(self._carried, 1)
        stacked = obs.observe(sw.xy, sw.heading, sw.radius, sim.table, sw.deployed, self._ids, self._start, flags,
                              stock=stock)
        return split(stacked, self.possible_agents)

    def step(self, actions: dict[str, Any]) -> tuple[dict, dict, dict, dict, dict]:
        """Act once: every agent's action, one step of the loop.

        Returns the observations, rewards, terminations, truncations and infos of the agents that acted.

        Raises:
            EnvError: The episode has ended, or an action is missing, unknown or outside its space.
        """
        sim = self.sim
        if not self.agents or sim is None:
            raise EnvError("step", "the episode has ended; call reset() first")
        turn, speed, wish = decode(self.config, self._act_space, actions, self.agents)
        ctl = sim.controller
        ctl.drop_rule.command(wish)
        if self.config.motion == "policy":
            ctl.explorer.command(turn, speed)
        released = ctl.released_by.copy()
        sim.step()
        self.steps += 1
        m = sim.metrics()
        gained = m.connected_coverage - self._connected_coverage
        self._connected_coverage = m.connected_coverage
        linked = self._linked()
        w = self.config.reward
        reward = (w.coverage * gained - w.cut_off * sim.dt * (~linked)
                  - w.router * (ctl.released_by - released))
        target = sim.books.coverage_target
        out_of_routers = self._carried is not None and not (ctl.left[self._ids] >= 1).any()
        done = (target is not None and m.coverage >= target) or bool(out_of_routers)
        truncated = not done and self.steps >= self.max_steps
        names = self.agents
        obs = self._observe()
        info = {"coverage": m.coverage, "connected_coverage": m.connected_coverage,
                "routers_deployed": m.routers_deployed, "t": sim.t}
        rewards = {a: float(reward[k]) for k, a in enumerate(names)}
        terms = dict.fromkeys(names, bool(done))
        truncs = dict.fromkeys(names, bool(truncated))
        infos = {a: {**info, "connected": bool(linked[k])} for k, a in enumerate(names)}
        if done or truncated:
            self.agents = []
        return obs, rewards, terms, truncs, infos

    def render(self) -> None:
        """Nothing to render here: record a run with ``amronet run --record`` and replay it."""

    def close(self) -> None:  # noqa: D102
        self.sim = None
