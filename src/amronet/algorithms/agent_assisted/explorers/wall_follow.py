"""The ``"wall-follow"`` explorer: what human searchers do in a building, the right-hand (or left-hand) rule.

An agent keeps a wall on one side at ``wall_distance`` (a fraction of its sonar range) and follows it: around
corners, through every doorway on that side into the room behind and out again along the room's walls. Walls that
touch each other form one chain, so following one visits every room that opens off it, room by room; that is how
search teams sweep a floor without a map. Agents alternate sides (even-numbered agents keep the wall on their right,
odd-numbered on their left), so two agents from one base station sweep in opposite directions.

Per step, from the agent's own sonar only:

* before it has met a wall it drives straight on (with the random explorer's heading noise), to find one;
* something ahead nearer than ``front`` (0.45 of the sonar range), or a refused move: turn away from the wall side
  by 60 degrees;
* the wall side is open (nothing within ``lost`` = 1.6 times the wall distance on that side: a corner or a doorway):
  turn toward it at ``turn_rate`` (90 degrees per second), which takes it around the corner or into the doorway;
* otherwise steer to keep the wall at ``wall_distance``: a heading correction proportional to the error, at most
  30 degrees per step.

It reads no map and no positions: the sonar ring alone (beam 0 straight ahead, beams counter-clockwise).
"""

from __future__ import annotations

import numpy as np

from amronet.algorithms.agent_assisted.explorers.base import EXPLORERS, Explorer
from amronet.engine.sensing import beam_angles
from amronet.engine.streams import draw_per_run

__all__ = ["WallFollowExplorer"]

WALL_FRACTION = 0.3
"""The wall distance kept, as a fraction of the sonar range (0.6 m for the Pioneer's 2 m sonars)."""
FRONT_FRACTION = 0.45
LOST_FACTOR = 1.6
TURN_RATE = np.pi / 2
"""Turn toward an open wall side, radians per second."""
GAIN = 1.5
"""Heading correction per metre of wall-distance error, radians."""


def _normal_draw(rng: np.random.Generator, m: int) -> tuple[np.ndarray]:
    return (rng.standard_normal(m),)


@EXPLORERS.register("wall-follow")
class WallFollowExplorer(Explorer):
    """The right-hand / left-hand rule with room entry (see the module docstring)."""

    def __init__(self, turn_noise: float, avoid_range: float, dt: float, r_c: float,
                 extent: tuple[float, float, float, float]) -> None:
        super().__init__(turn_noise, avoid_range, dt, r_c, extent)
        self._met_wall: np.ndarray | None = None
        self._side: np.ndarray | None = None

    def steer(self, heading: np.ndarray, who: np.ndarray, scans: np.ndarray, sensor_range: float,  # noqa: D102
              refused: np.ndarray, rng: np.random.Generator, xy: np.ndarray, deployed_xy: np.ndarray) -> None:
        m = len(who)
        if self._side is None or len(self._side) != m:
            self._side = np.where(np.arange(m) % 2 == 0, -1.0, 1.0)  # -1: wall on the right, +1: on the left
            self._met_wall = np.zeros(m, dtype=bool)
        assert self._met_wall is not None
        side = self._side
        angles = beam_angles(scans.shape[1])
        rel = np.angle(np.exp(1j * angles))  # (-pi, pi]
        wall_d = WALL_FRACTION * sensor_range
        front_sel = np.abs(rel) <= np.radians(35)
        front = scans[:, front_sel].min(axis=1)
        right_sel = (rel >= -np.radians(120)) & (rel <= -np.radians(50))
        left_sel = (rel <= np.radians(120)) & (rel >= np.radians(50))
        beside = np.where(side < 0, scans[:, right_sel].min(axis=1), scans[:, left_sel].min(axis=1))
        self._met_wall |= beside < LOST_FACTOR * wall_d
        self._met_wall |= front < FRONT_FRACTION * sensor_range
        (normal,) = draw_per_run(rng, who, _normal_draw)
        turn = self.turn_noise * np.sqrt(self.dt) * normal
        blocked = refused | (front < FRONT_FRACTION * sensor_range)
        lost = ~blocked & (beside >= LOST_FACTOR * wall_d)
        follow = ~blocked & ~lost
        turn = np.where(blocked & self._met_wall, -side * np.radians(60), turn)
        turn = np.where(blocked & ~self._met_wall, np.pi / 2, turn)
        turn = np.where(lost & self._met_wall, side * TURN_RATE * self.dt, turn)
        correction = np.clip(GAIN * (beside - wall_d), -np.radians(30), np.radians(30))
        turn = np.where(follow, side * correction, turn)
        heading[who] = np.angle(np.exp(1j * (heading[who] + turn)))
