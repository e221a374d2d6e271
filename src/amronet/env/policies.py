"""The paper's rules as policies of an observation: scripted baselines a learned policy is compared with.

* :class:`LastReference` -- the paper's greedy rule (section 4.1): wish to drop (an agent) or settle (a router) when
  every relay it hears is at least ``(1 - loss_margin) r_c`` away (the observation's ``relay`` distance);
* :class:`LinkQuality` -- the location-free rule (paper section 6; ``drop_rule: link-quality``): wish when the
  moving average of the best margin to a relay it hears falls below ``drop_margin_db``, or the raw margin below
  ``loss_margin_db``; the average starts again after the agent's own drop (its ``dropped`` flag).

Each reads only the observation, and run through an environment with ``motion: builtin`` it deploys exactly what the
built-in controller with that rule deploys: the same seed gives the same routers in the same places
(``tests/test_env_policies.py``). With ``motion: policy`` a policy also needs a motion; the default,
:func:`straight_avoiding`, drives straight on and turns left before obstacles.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from typing import Any, Protocol

import numpy as np

from amronet.engine.sensing import beam_angles
from amronet.env.config import EnvConfig

__all__ = ["LastReference", "LinkQuality", "Motion", "ScriptedPolicy", "straight_avoiding"]

Motion = Callable[[Mapping[str, np.ndarray]], tuple[float, float]]
"""A motion of an observation: ``(turn as a fraction of max_turn in [-1, 1], speed fraction in [0, 1])``."""

CLEARANCE_M = 0.5
""":func:`straight_avoiding` turns when a reading within 45 degrees of its heading is nearer than this."""


def straight_avoiding(obs: Mapping[str, np.ndarray]) -> tuple[float, float]:
    """Straight on at top speed; a full left turn (and half speed) when something ahead is nearer than 0.5 m."""
    scan = obs["scan"]
    ahead = np.cos(beam_angles(len(scan))) >= np.cos(np.pi / 4) - 1e-12
    if np.any(scan[ahead] < CLEARANCE_M):
        return 1.0, 0.5
    return 0.0, 1.0


class _Env(Protocol):
    config: EnvConfig
    setup: Any
    flags: tuple[str, ...]


class ScriptedPolicy:
    """A policy of observations: each robot's wish from its own observation, and a motion when the actions steer.

    Args:
        env: The environment (its configuration says how to encode the actions).
        motion: The motion under ``motion: policy`` (default :func:`straight_avoiding`).
    """

    def __init__(self, env: _Env, motion: Motion | None = None) -> None:
        self.config = env.config
        self.motion = motion or straight_avoiding
        sc = env.setup.run
        self.r_c = float(sc.radio.r_c)
        self.dt = float(sc.sim.dt)
        self.params = sc.algorithm_params()
        self.flags = tuple(env.flags)

    def reset(self) -> None:
        """Forget what the robots remembered (call after ``env.reset``)."""

    def wishes(self, observations: Mapping[str, Mapping[str, np.ndarray]]) -> dict[str, bool]:
        """Each robot's wish (drop, settle)."""
        raise NotImplementedError

    def __call__(self, observations: Mapping[str, Mapping[str, np.ndarray]]) -> dict[str, Any]:
        """The actions of the robots whose observations are given, encoded for the environment's action space."""
        wishes = self.wishes(observations)
        out: dict[str, Any] = {}
        for name, obs in observations.items():
            wish = wishes[name]
            if self.config.motion == "builtin":
                out[name] = (np.array([float(wish)], np.float32) if self.config.actions == "continuous"
                             else int(wish))
                continue
            turn, speed = self.motion(obs)
            if self.config.actions == "continuous":
                out[name] = np.array([turn, speed, float(wish)], np.float32)
            else:
                motion = 4 if speed <= 0 else 1 if turn > 0.5 else 2 if turn < -0.5 else 0
                out[name] = np.array([motion, int(wish)])
        return out


class LastReference(ScriptedPolicy):
    """The paper's rule: wish when the nearest relay heard is at least ``(1 - loss_margin) r_c`` away."""

    def __init__(self, env: _Env, motion: Motion | None = None) -> None:
        super().__init__(env, motion)
        band = float(self.params.loss_margin) * self.r_c  # (as the controllers compute it, to the last bit)
        self.r_eff = self.r_c - band

    def wishes(self, observations: Mapping[str, Mapping[str, np.ndarray]]) -> dict[str, bool]:  # noqa: D102
        return {name: bool(obs["relay"][0] >= 0.5 and obs["relay"][1] >= self.r_eff)
                for name, obs in observations.items()}


class LinkQuality(ScriptedPolicy):
    """The link-quality rule on the observation's best relay margin (its parameters as ``drop_rule: link-quality``'s).

    Args:
        env: The environment.
        motion: The motion under ``motion: policy``.
        drop_margin_db: Wish when the smoothed best margin falls below this (dB).
        loss_margin_db: Wish at once when the raw best margin falls below this (dB).
        smoothing_s: Time constant of the margin's moving average (seconds; 0: none).
    """

    def __init__(self, env: _Env, motion: Motion | None = None, drop_margin_db: float = 8.0,
                 loss_margin_db: float = 1.0, smoothing_s: float = 0.5) -> None:
        super().__init__(env, motion)
        self.drop_margin_db = drop_margin_db
        self.loss_margin_db = loss_margin_db
        self.alpha = 1.0 if smoothing_s == 0 else 1.0 - float(np.exp(-self.dt / smoothing_s))
        self.smoothed: dict[str, float] = {}

    def reset(self) -> None:  # noqa: D102
        self.smoothed = {}

    def wishes(self, observations: Mapping[str, Mapping[str, np.ndarray]]) -> dict[str, bool]:  # noqa: D102
        out = {}
        for name, obs in observations.items():
            heard = obs["relay"][0] >= 0.5
            best = float(obs["relay"][2]) if heard else -np.inf
            old = self.smoothed.get(name, np.nan)
            if "dropped" in self.flags and obs["flags"][self.flags.index("dropped")]:
                old = np.nan  # a fresh router next to it: the history starts again
            new = best if np.isnan(old) else old + self.alpha * (best - old)
            if not np.isfinite(best):
                new = np.nan
            self.smoothed[name] = new
            out[name] = bool(heard and (new < self.drop_margin_db or best < self.loss_margin_db))
        return out
