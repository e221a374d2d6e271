"""The scenario an environment runs: the user's, with its agents' decisions handed to the policy."""

from __future__ import annotations

from pathlib import Path
from typing import Any

from amronet.env.config import EnvConfig
from amronet.env.errors import EnvError
from amronet.scenario import Scenario, load_scenario

__all__ = ["EnvScenario", "prepare"]

ScenarioRef = Scenario | dict[str, Any] | str | Path


class EnvScenario:
    """A scenario made ready for an environment.

    Args:
        scenario: The user's scenario (a :class:`~amronet.scenario.Scenario`, a dict, a YAML path or a preset name).
        overrides: Dotted-path fields to replace first, e.g. ``{"radio.model": "multi-wall"}``.
        algorithm: The algorithm the environment drives (``agent-assisted`` or ``self-spreading``).
        config: The environment's configuration.

    Attributes:
        user: The user's scenario, validated.
        run: The scenario the loop runs: the wish to drop (settle) and, with ``motion: policy``, the motion come from
            the actions (the ``external`` drop rule and explorer, or stop rule and walk); its time limit covers
            ``max_steps``.
        max_steps: The truncation step.

    Raises:
        ScenarioError: The scenario or an override is invalid (unknown preset, field, value).
        EnvError: The scenario's algorithm is not the environment's, or it gives agents paths to follow.
    """

    def __init__(self, scenario: ScenarioRef, overrides: dict[str, Any] | None, algorithm: str,
                 config: EnvConfig) -> None:
        user = load_scenario(scenario, overrides)
        if user.algorithm.name != algorithm:
            other = "router_env" if algorithm == "agent-assisted" else "deployment_env"
            raise EnvError("scenario", f"its algorithm is {user.algorithm.name!r}; this environment drives "
                           f"{algorithm} (use {other} for the other one)")
        if algorithm == "agent-assisted" and user.agents.trajectories is not None:
            raise EnvError("scenario", "agents.trajectories gives the agents their paths; the environment's agents "
                           "choose theirs: leave agents.trajectories out")
        dt = user.sim.dt
        self.max_steps = config.max_steps if config.max_steps is not None else max(1, round(user.sim.time_limit / dt))
        params: dict[str, Any] = dict(user.algorithm.params)
        if algorithm == "agent-assisted":
            params.update({"drop_rule": "external", "drop": {}})
            if config.motion == "policy":
                params["explorer"] = "external"
        else:
            params["stop_rule"] = "external"
            if config.motion == "policy":
                params["walk"] = "external"
        self.user = user
        self.run = load_scenario(user, {"algorithm.params": params,
                                        "sim.time_limit": max(user.sim.time_limit, self.max_steps * dt)})


def prepare(scenario: ScenarioRef, overrides: dict[str, Any] | None, algorithm: str, config: EnvConfig
            ) -> EnvScenario:
    """:class:`EnvScenario` of the arguments."""
    return EnvScenario(scenario, overrides, algorithm, config)
