"""The sense and move phases of a step, as the loop runs them one by one (:meth:`amronet.sim.loop.Loop.step`).

Apart from the loop so that a compiled step (:mod:`amronet.algorithms.agent_assisted.fast`) can run them too, in the
steps it
hands back to the reference.
"""

from __future__ import annotations

import numpy as np

from amronet.algorithms.base import Command, Controller, Readings
from amronet.engine.motion import drive
from amronet.engine.radio import NeighbourTable
from amronet.engine.robots import MOBILE_STATES, Swarm
from amronet.engine.sensing import range_scan
from amronet.world.occupancy import OccupancyMap

__all__ = ["move", "sense"]


def sense(controller: Controller, sw: Swarm, omap: OccupancyMap, table: NeighbourTable) -> Readings:
    """The sense phase: the range rings of every moving robot (none when the controller reads none)."""
    if not controller.needs_range_readings:
        return Readings({})
    mobile = np.flatnonzero(sw.in_states(MOBILE_STATES))
    groups = {}
    if len(mobile) == 0:
        return Readings(groups)
    kinds = sw.model[mobile]
    for m, model in enumerate(sw.models):
        who = mobile[kinds == m]
        if len(who):
            scans = range_scan(omap, sw.xy, sw.heading, who, model.sensor_beams, model.sensor_range,
                               radius=sw.radius, table=table)
            groups[m] = (who, scans)
    return Readings(groups)


def move(controller: Controller, command: Command, sw: Swarm, omap: OccupancyMap, table: NeighbourTable | None,
         dt: float, bodies: bool) -> None:
    """The move phase: drive the movers, add up distances and tell the controller which moves were refused."""
    movers = command.movers
    refused, travelled = drive(omap, sw.xy, movers, sw.heading[movers], command.speed * dt, sw.radius,
                               bodies=bodies, table=table)
    sw.distance[movers] += travelled
    controller.after_move(movers, refused)
