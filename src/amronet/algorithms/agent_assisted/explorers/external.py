"""The ``"external"`` explorer: agents move as a policy outside the controller commands, step by step.

It is what :mod:`amronet.env` drives: before every step the environment hands each agent's command over
(:meth:`ExternalExplorer.command`: a turn in radians and a speed as a fraction of the agent's top speed), and the
step's :meth:`~ExternalExplorer.steer` applies it. Everything else of agent-assisted deployment -- reference tracking,
releasing routers, triangles, tethering, the move with its collision checks -- stays the controller's. A run of a
scenario that names this explorer without an environment to command it stops at its first step with one line.
"""

from __future__ import annotations

import numpy as np

from amronet.algorithms.agent_assisted.explorers.base import EXPLORERS, Explorer
from amronet.errors import ScenarioError

__all__ = ["ExternalExplorer"]


@EXPLORERS.register("external")
class ExternalExplorer(Explorer):
    """Agents turn and drive as commanded from outside each step (the motion actions of :mod:`amronet.env`)."""

    external = True
    """Driven from outside: no warm-up run, no run of its own (:mod:`amronet.env` commands it)."""

    def __init__(self, turn_noise: float, avoid_range: float, dt: float, r_c: float,
                 extent: tuple[float, float, float, float]) -> None:
        super().__init__(turn_noise, avoid_range, dt, r_c, extent)
        self._turn: np.ndarray | None = None
        self._speed = np.zeros(0)

    def command(self, turn: np.ndarray, speed: np.ndarray) -> None:
        """The next step's command, one entry per agent: a turn (radians) and a speed fraction in ``[0, 1]``."""
        self._turn = np.asarray(turn, dtype=float)
        self._speed = np.asarray(speed, dtype=float)

    def steer(self, heading: np.ndarray, who: np.ndarray, scans: np.ndarray, sensor_range: float,  # noqa: D102
              refused: np.ndarray, rng: np.random.Generator, xy: np.ndarray, deployed_xy: np.ndarray) -> None:
        if self._turn is None:
            raise ScenarioError("algorithm.params.explorer", "the 'external' explorer moves agents by the actions "
                                "of amronet.env (deployment_env); to run a scenario alone choose another explorer, "
                                "e.g. frontier")
        h = heading[who] + self._turn
        heading[who] = (h + np.pi) % (2.0 * np.pi) - np.pi
        self._turn = None  # one command, one step

    def speed(self, max_speed: np.ndarray) -> np.ndarray:
        """The commanded fractions of the agents' top speeds."""
        return max_speed * self._speed
