"""What a compiled step reads of the map and of the bodies around its robots (every compiled step shares it)."""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from amronet.engine.robots import RobotModel
from amronet.engine.sensing import beam_angles, body_table
from amronet.engine.table import NeighbourTable
from amronet.world.space import clearance

if TYPE_CHECKING:
    from amronet.sim.loop import Loop

__all__ = ["Surroundings"]

CSR = tuple[np.ndarray, np.ndarray, np.ndarray]


class Surroundings:
    """The map's grid for the rings and the moves, the movers' sensor ring, and the bodies near each robot.

    Args:
        loop: The loop.
        model: The movers' robot model (one for all of them).
        movers: Mask or indices of the robots that may move when no robot is ever added or changed (self-spreading,
            the potential field): the reach within which two bodies may touch after a step is then fixed
            (:meth:`bodies`). ``None``: robots come and go (agent-assisted runs), reaches are given per step
            (:meth:`near`).
    """

    def __init__(self, loop: Loop, model: RobotModel, movers: np.ndarray | None = None) -> None:
        omap = loop.world.omap
        self.swarm = loop.swarm if movers is None else None
        """The robots whose largest body :meth:`largest_radius` follows (``None``: fixed reaches, it never changes)."""
        self.grid = (omap.blocked.view(np.uint8), clearance(omap), float(omap.origin[0]), float(omap.origin[1]),
                     float(omap.resolution))
        self.angles = beam_angles(model.sensor_beams)
        self.sensor_range = float(model.sensor_range)
        self.collisions = loop.scenario.sim.robot_collisions
        self._biggest = (loop.swarm.radius, float(loop.swarm.radius.max()))
        self._empty: dict[int, CSR] = {}
        self.sense_reach = float(self.sensor_range + self._biggest[1])
        self.drive_reach = 0.0
        """Fixed reaches only: every pair that could touch after this step's longest move is this close (with room
        for rounding: the kernels' exact reach, from lengths rounded through speeds, is at most this)."""
        if movers is not None:
            fastest = float(loop.swarm.max_speed[movers].max(initial=0.0))
            self.drive_reach = (2.0 * self._biggest[1] + 2.0 * fastest * loop.dt) * (1.0 + 1e-9) + 1e-12

    def largest_radius(self) -> float:
        """The largest body radius now (kept while the robots stay the same: robots are only ever added)."""
        radius = self._biggest[0] if self.swarm is None else self.swarm.radius
        if radius is not self._biggest[0]:
            self._biggest = (radius, float(radius.max()))
        return self._biggest[1]

    def no_bodies(self, n: int) -> CSR:
        """An empty neighbour list of ``n`` robots."""
        if n not in self._empty:
            self._empty[n] = (np.zeros(n + 1, dtype=np.int64), np.zeros(0, dtype=np.int32), np.zeros(0))
        return self._empty[n]

    def near(self, xy: np.ndarray, table: NeighbourTable, reach: float) -> CSR:
        """Every pair of robots within ``reach`` (:func:`body_table`); none for a single robot."""
        return body_table(xy, reach, table) if len(xy) > 1 else self.no_bodies(len(xy))

    def bodies(self, xy: np.ndarray, table: NeighbourTable, sense: bool = True) -> tuple:
        """``(several, sense CSR, drive with bodies, drive CSR)`` for this step, with the fixed reaches."""
        several = len(xy) > 1
        s_csr = self.near(xy, table, self.sense_reach) if sense else self.no_bodies(len(xy))
        drive_bodies = self.collisions and several
        d_csr = self.near(xy, table, self.drive_reach) if drive_bodies else self.no_bodies(len(xy))
        return several, s_csr, drive_bodies, d_csr
