"""What both environments share: one observation and one action space for every agent, and unknown names refused."""

from __future__ import annotations

from gymnasium import spaces
from pettingzoo import ParallelEnv

from amronet.env.errors import EnvError

__all__ = ["SharedSpaces"]


class SharedSpaces(ParallelEnv):
    """A PettingZoo environment whose agents all have the same spaces (``_obs_space``, ``_act_space``)."""

    possible_agents: list[str]
    _obs_space: spaces.Dict | None
    _act_space: spaces.Space

    def observation_space(self, agent: str) -> spaces.Dict:
        """The observation space of ``agent`` (one object for every agent, as PettingZoo asks)."""
        self._known(agent)
        assert self._obs_space is not None
        return self._obs_space

    def action_space(self, agent: str) -> spaces.Space:
        """The action space of ``agent`` (one object for every agent)."""
        self._known(agent)
        return self._act_space

    def _known(self, agent: str) -> None:
        if agent not in self.possible_agents:
            names = self.possible_agents
            shown = ", ".join(names) if len(names) <= 3 else ", ".join(names[:3]) + ", ..."
            raise EnvError("agent", f"{agent!r} is not one of {shown}")
