"""The front door: an environment from a scenario (a preset name, a YAML path, a dict or a Scenario)."""

from __future__ import annotations

from typing import Any

from amronet.env.agents import DeploymentEnv
from amronet.env.config import EnvConfig, RewardWeights
from amronet.env.routers import RouterEnv
from amronet.env.scenarios import EnvScenario, ScenarioRef

__all__ = ["deployment_env", "router_env"]


def _config(max_steps: int | None, motion: str, actions: str, reward: RewardWeights | None,
            options: dict[str, Any]) -> EnvConfig:
    return EnvConfig(max_steps=max_steps, motion=motion, actions=actions,  # type: ignore[arg-type]
                     reward=reward if reward is not None else RewardWeights(), **options)


def deployment_env(scenario: ScenarioRef = "agent-assisted-office", overrides: dict[str, Any] | None = None, *,
                   max_steps: int | None = None, motion: str = "policy", actions: str = "continuous",
                   reward: RewardWeights | None = None, seed: int | None = None, **options: Any) -> DeploymentEnv:
    """The agent-assisted environment (:mod:`amronet.env.agents`): agents explore and drop routers.

    Args:
        scenario: An agent-assisted scenario: a preset name, a YAML path, a dict or a Scenario.
        overrides: Dotted-path fields to replace, e.g. ``{"radio.model": "multi-wall"}``.
        max_steps: Truncation (default: the scenario's ``sim.time_limit / sim.dt``).
        motion: ``policy`` (actions steer) or ``builtin`` (the scenario's explorer steers; actions drop).
        actions: ``continuous`` or ``discrete`` (:mod:`amronet.env.actions`).
        reward: The reward's weights.
        seed: Seed of the episodes reset without a seed.
        **options: Further :class:`~amronet.env.config.EnvConfig` fields (``max_turn``, ``links``, ``patch``,
            ``patch_cell``).

    Raises:
        ScenarioError: Unknown preset, invalid scenario or override.
        EnvError: An invalid argument (e.g. a negative ``max_steps``), or a scenario of another algorithm.
    """
    config = _config(max_steps, motion, actions, reward, options)
    return DeploymentEnv(EnvScenario(scenario, overrides, "agent-assisted", config), config, seed)


def router_env(scenario: ScenarioRef = "self-spreading-obstacles-6x6", overrides: dict[str, Any] | None = None, *,
               max_steps: int | None = None, motion: str = "policy", actions: str = "continuous",
               reward: RewardWeights | None = None, seed: int | None = None, **options: Any) -> RouterEnv:
    """The self-spreading environment (:mod:`amronet.env.routers`): the routers walk and settle.

    Arguments as :func:`deployment_env`'s, for a self-spreading scenario (``motion: builtin``: the scenario's walk
    moves the routers, actions settle them).
    """
    config = _config(max_steps, motion, actions, reward, options)
    return RouterEnv(EnvScenario(scenario, overrides, "self-spreading", config), config, seed)
