"""The environments' actions: their spaces, the checks, and what they command.

With ``motion: policy`` an action is a motion and a wish:

* ``continuous``: ``Box([-1, 0, 0], [1, 1, 1])`` -- ``[turn, speed, wish]``: turn by ``turn x max_turn`` radians,
  drive at ``speed`` times the top speed, wish (to drop a router; to settle, for routers) when ``wish >= 0.5``;
* ``discrete``: ``MultiDiscrete([5, 2])`` -- ``[motion, wish]``, motion 0 straight on, 1 turn left by ``max_turn``,
  2 turn right by ``max_turn``, 3 turn around, 4 stop (speed 0); every other motion at top speed.

With ``motion: builtin`` the scenario's explorer (walk) moves the robot and the action is the wish alone:
``Box([0], [1])`` (``continuous``, wish when ``>= 0.5``) or ``Discrete(2)`` (``discrete``).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np
from gymnasium import spaces

from amronet.env.config import EnvConfig
from amronet.env.errors import EnvError

__all__ = ["DISCRETE_MOTIONS", "action_space", "decode"]

DISCRETE_MOTIONS = ("straight", "left", "right", "around", "stop")
"""What the discrete motions 0-4 do."""


def action_space(config: EnvConfig) -> spaces.Space:
    """One robot's action space under ``config``."""
    if config.motion == "builtin":
        return spaces.Box(0.0, 1.0, (1,), np.float32) if config.actions == "continuous" else spaces.Discrete(2)
    if config.actions == "continuous":
        return spaces.Box(np.array([-1.0, 0.0, 0.0], np.float32), np.array([1.0, 1.0, 1.0], np.float32),
                          (3,), np.float32)
    return spaces.MultiDiscrete([len(DISCRETE_MOTIONS), 2])


def _checked(space: spaces.Space, action: object, where: str) -> np.ndarray:
    """The action as an array of the space's type; :class:`EnvError` when it is not in the space."""
    try:
        value = np.asarray(action, dtype=float)
        if isinstance(space, spaces.Box):
            ok = value.shape == space.shape and bool(np.all(np.isfinite(value))) and space.contains(
                value.astype(space.dtype))
        else:
            ok = bool(np.all(value == np.round(value))) and space.contains(value.astype(np.int64).reshape(space.shape))
    except (TypeError, ValueError):
        ok = False
    if not ok:
        raise EnvError(where, f"{action!r} is outside the action space {space}; sample one with "
                              "env.action_space(agent).sample() or see docs/environment.md")
    return value.reshape(-1)


def decode(config: EnvConfig, space: spaces.Space, actions: Mapping[str, object], names: Sequence[str]
           ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Turns (radians), speed fractions and wishes of the robots ``names`` from their actions.

    Raises:
        EnvError: An action is missing, outside the space, or given for a robot that is not acting.
    """
    unknown = sorted(set(actions) - set(names), key=str)
    if unknown:
        raise EnvError("actions", f"{unknown[0]!r} is not an acting agent; give actions for env.agents only")
    missing = [name for name in names if name not in actions]
    if missing:
        raise EnvError("actions", f"no action for {missing[0]!r}; give one for every agent in env.agents")
    m = len(names)
    turn, speed, wish = np.zeros(m), np.ones(m), np.zeros(m, dtype=bool)
    for k, name in enumerate(names):
        a = _checked(space, actions[name], f"actions[{name}]")
        if config.motion == "builtin":
            wish[k] = a[0] >= 0.5
        elif config.actions == "continuous":
            turn[k], speed[k], wish[k] = a[0] * config.max_turn, a[1], a[2] >= 0.5
        else:
            motion = int(a[0])
            turn[k] = {1: config.max_turn, 2: -config.max_turn, 3: np.pi}.get(motion, 0.0)
            speed[k] = 0.0 if motion == 4 else 1.0
            wish[k] = a[1] == 1
    return turn, speed, wish


def decode_array(config: EnvConfig, space: spaces.Space, actions: np.ndarray, live: np.ndarray
                 ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """:func:`decode` for a vectorised environment: ``actions`` ``(G, A, ...)``; only entries where ``live`` counts.

    Raises:
        EnvError: A live entry is outside the space, or the array has the wrong shape.
    """
    a = np.asarray(actions, dtype=float)
    g, n = live.shape
    per = () if isinstance(space, spaces.Discrete) else space.shape
    if a.shape != (g, n, *per):
        raise EnvError("actions", f"shape {a.shape} is not (runs, agents, ...) = {(g, n, *per)}")
    flat = a.reshape(g * n, -1)
    lo = np.zeros(flat.shape[1]) if not isinstance(space, spaces.Box) else space.low.astype(float)
    hi = (space.high.astype(float) if isinstance(space, spaces.Box)
          else np.array([space.n - 1]) if isinstance(space, spaces.Discrete) else space.nvec - 1.0)
    on = live.reshape(-1)
    inside = (flat >= lo) & (flat <= hi)  # (the bounds are finite: NaN and infinities fall outside)
    if not isinstance(space, spaces.Box):
        inside &= flat == np.round(flat)
    bad = on & ~inside.all(axis=1)
    if bad.any():
        k = int(np.flatnonzero(bad)[0])
        raise EnvError(f"actions[{k // n}, {k % n}]", f"{flat[k].tolist()} is outside the action space {space}")
    if config.motion == "builtin":
        turn, speed, wish = np.zeros(g * n), np.ones(g * n), flat[:, 0] >= 0.5
    elif config.actions == "continuous":
        turn, speed, wish = flat[:, 0] * config.max_turn, flat[:, 1].copy(), flat[:, 2] >= 0.5
    else:
        motion = flat[:, 0].astype(np.int64)  # (0-4 where live; entries not live are not read)
        turns = np.array([0.0, config.max_turn, -config.max_turn, np.pi, 0.0])
        turn = turns.take(motion, mode="clip")
        speed = np.where(motion == 4, 0.0, 1.0)
        wish = flat[:, 1] == 1
    return turn.reshape(g, n), speed.reshape(g, n), wish.reshape(g, n)
