"""Self-spreading routers commanded from outside: the ``external`` walk and stop rule (what :mod:`amronet.env` drives).

Before every step the environment hands each router's command over (:meth:`ExternalCommands.command`): a turn in
radians, a speed as a fraction of its top speed, and whether it wishes to settle. With ``walk: external`` the
exploring routers turn and drive as commanded (instead of a walk rule); with ``stop_rule: external`` an exploring
router that wishes to settle and hears a reference stops and becomes a reference, as a router the paper's rule stops
does (reference tracking, triangles and triangle routers stay the controller's). A policy that wishes exactly when
the paper's rule fires deploys exactly what it deploys (:mod:`amronet.env.policies`). Per-robot arrays only, so runs of
a batch stay independent. A run of a scenario that names either without an environment stops at its first step.
"""

from __future__ import annotations

import numpy as np

from amronet.errors import ScenarioError

__all__ = ["EXTERNAL", "ExternalCommands"]

EXTERNAL = "external"
"""The name of the walk and of the stop rule a policy outside commands."""


class ExternalCommands:
    """The routers' commands for the next step, one entry per robot.

    Args:
        n: Number of robots.
        field: The scenario field that chose commands from outside (for the error of a run without them).
    """

    def __init__(self, n: int, field: str) -> None:
        self.turn = np.zeros(n)
        """Turn of each robot's heading, radians."""
        self.speed = np.zeros(n)
        """Speed of each robot as a fraction of its top speed, ``[0, 1]``."""
        self.settle = np.zeros(n, dtype=bool)
        """Whether each robot wishes to settle (stop and become a reference)."""
        self.field = field
        self._given = False

    def command(self, turn: np.ndarray, speed: np.ndarray, settle: np.ndarray) -> None:
        """Set the next step's commands of every robot (entries of robots that do not explore are not read)."""
        self.turn[:] = turn
        self.speed[:] = speed
        self.settle[:] = settle
        self._given = True

    def check(self) -> None:
        """Raise unless an environment gives the commands (a scenario run alone names ``external``).

        Raises:
            ScenarioError: No environment commands the routers.
        """
        if not self._given:
            raise ScenarioError(self.field, "'external' takes its commands from amronet.env (router_env); to run "
                                "a scenario alone choose another, e.g. random (walk) or distance (stop_rule)")

    def steer(self, heading: np.ndarray, who: np.ndarray, max_speed: np.ndarray) -> np.ndarray:
        """Turn the walking routers ``who`` as commanded; their speeds ``(M,)`` from their top speeds ``max_speed``."""
        self.check()
        h = heading[who] + self.turn[who]
        heading[who] = (h + np.pi) % (2.0 * np.pi) - np.pi
        return max_speed * self.speed[who]

    def wishes(self, who: np.ndarray) -> np.ndarray:
        """Which of the exploring routers ``who`` wish to settle now."""
        self.check()
        return self.settle[who].copy()
