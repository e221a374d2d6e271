"""What an environment is made of besides its scenario: its horizon, its actions, its observation, its reward."""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Literal

from amronet.env.errors import EnvError

__all__ = ["EnvConfig", "RewardWeights"]

ActionKind = Literal["continuous", "discrete"]


def _finite(value: object, name: str, *, low: float = 0.0, low_open: bool = False) -> float:
    """``value`` as a float, or :class:`EnvError` unless it is a finite number ``>= low`` (``> low`` when open)."""
    if isinstance(value, bool) or not isinstance(value, int | float) or not math.isfinite(value):
        raise EnvError(name, f"{value!r} is not a finite number")
    if value < low or (low_open and value == low):
        raise EnvError(name, f"{value!r} must be {'>' if low_open else '>='} {low:g}")
    return float(value)


def _count(value: object, name: str, low: int, high: int) -> int:
    """``value`` as an int in ``[low, high]``, or :class:`EnvError`."""
    if isinstance(value, bool) or not isinstance(value, int) or not low <= value <= high:
        raise EnvError(name, f"{value!r} must be an integer in [{low}, {high}]")
    return int(value)


@dataclass(frozen=True)
class RewardWeights:
    """The weights of the reward's three terms (see the environments' docs; each ``>= 0``).

    Attributes:
        coverage: Per unit of connected coverage gained (fraction of the reachable area, Eq. (1) over the nodes
            linked to a base station), shared by every agent of the team.
        cut_off: Per second an agent (router) has no path to any base station, its own.
        router: Per router an agent puts down (a router settles, in the router environment), its own.
    """

    coverage: float = 100.0
    cut_off: float = 1.0
    router: float = 0.5

    def __post_init__(self) -> None:
        for name in ("coverage", "cut_off", "router"):
            _finite(getattr(self, name), f"reward.{name}")


@dataclass(frozen=True)
class EnvConfig:
    """How an environment steps, what its agents do and see, and what they are rewarded for.

    Attributes:
        max_steps: Truncation: the episode ends after this many steps (``None``: the scenario's
            ``sim.time_limit / sim.dt``).
        motion: ``policy``: the actions steer (a turn and a speed); ``builtin``: the scenario's explorer (agents)
            or walk (routers) moves them, and the action is only whether to drop (settle).
        actions: ``continuous`` (a ``Box``) or ``discrete`` (``MultiDiscrete``, or ``Discrete(2)`` with ``builtin``
            motion).
        max_turn: The largest turn of one step (radians), what a continuous turn of 1 and the discrete turns mean.
        links: How many heard links the observation lists (the strongest first).
        patch: Side of the local occupancy patch in cells (0: no patch).
        patch_cell: Side of a patch cell, metres.
        reward: The reward's weights.
    """

    max_steps: int | None = None
    motion: Literal["policy", "builtin"] = "policy"
    actions: ActionKind = "continuous"
    max_turn: float = math.pi / 4
    links: int = 8
    patch: int = 0
    patch_cell: float = 0.25
    reward: RewardWeights = field(default_factory=RewardWeights)

    def __post_init__(self) -> None:
        if self.max_steps is not None:
            _count(self.max_steps, "max_steps", 1, 10**9)
        if self.motion not in ("policy", "builtin"):
            raise EnvError("motion", f"{self.motion!r} is not one of: policy, builtin")
        if self.actions not in ("continuous", "discrete"):
            raise EnvError("actions", f"{self.actions!r} is not one of: continuous, discrete")
        turn = _finite(self.max_turn, "max_turn", low_open=True)
        if turn > math.pi:
            raise EnvError("max_turn", f"{turn!r} must be at most pi (a half turn)")
        _count(self.links, "links", 1, 256)
        _count(self.patch, "patch", 0, 255)
        _finite(self.patch_cell, "patch_cell", low_open=True)
        if not isinstance(self.reward, RewardWeights):
            raise EnvError("reward", "give a RewardWeights(coverage=..., cut_off=..., router=...)")
