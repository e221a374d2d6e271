"""The routers that move after an agent released them: triangle routers, strip routers, relocating routers.

:class:`Movers` is mixed into :class:`~amronet.algorithms.agent_assisted.controller.AgentAssisted`; the names it
declares are the controller's. Each step, once the agents are steered, :meth:`Movers.movers_command` steers these
routers and returns the command that moves them with the agents.

Triangle routers drive to their goal points (:class:`~amronet.algorithms.common.goto.GoalSteering`) and settle on
arrival or when they give up. Ours, where links are not decided by distance alone
(:attr:`~amronet.algorithms.base.Setup.links_by_distance` false: walls, shadowing, packet loss), the *link test at
settling*: a triangle router settles only where its own table row holds one of its two references; otherwise it drives
back to where it last heard one (:meth:`~amronet.algorithms.common.goto.GoalSteering.check_links`). One that hears
neither after that retreat, or never heard one, settles where it is all the same (an agent-assisted router has no
exploring of its own to fall back on): it is counted in :attr:`Movers.triangles_cut_off`.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from amronet.algorithms.agent_assisted.retrace import Retracer
from amronet.algorithms.base import Command, StepInput
from amronet.engine.network import agents_connected
from amronet.engine.robots import State

if TYPE_CHECKING:
    from collections.abc import Callable

    from amronet.algorithms.agent_assisted.explorers import Explorer
    from amronet.algorithms.agent_assisted.relocate import Relocator
    from amronet.algorithms.agent_assisted.strip_driving import StripDrivers
    from amronet.algorithms.common.goto import GoalSteering
    from amronet.engine.robots import Swarm

__all__ = ["Movers"]


class Movers:
    """Steering the released routers that move, and the step's command (a mixin of the controller)."""

    swarm: Swarm
    dt: float
    r_eff: float
    agents: np.ndarray
    agent_model: int
    bases: np.ndarray
    agent_speed: np.ndarray
    explorer: Explorer
    steering: GoalSteering
    links_by_distance: bool
    moving_triangles: int
    triangles_cut_off: int
    strips: StripDrivers | None
    relocator: Relocator | None
    _nodes_changed: Callable[[], None]

    def movers_command(self, step: StepInput, n_before: int) -> Command:
        """The end of :meth:`decide` once the agents are steered: the other movers steer; the command for them all.

        The triangle, strip and relocating routers steer; the command moves them with the agents. A compiled step
        that steers the agents itself (:mod:`amronet.algorithms.agent_assisted.stretch`) finishes a step here.
        """
        sw = self.swarm
        agents = self.agents
        speed = self.explorer.speed(self.agent_speed)
        if isinstance(self.relocator, Retracer):  # cut-off agents back up their own path
            contact = agents_connected(step.table, agents, self.bases, sw.relaying)
            speed = self.relocator.steer_agents(step.t, contact, sw, step.readings.of(agents, self.agent_model),
                                                sw.models[self.agent_model].sensor_range, speed, self.dt)
        movers, speeds = [agents], [speed]

        # triangle routers released before this step drive to their goals
        if self.moving_triangles:
            tri = np.flatnonzero(sw.state[:n_before] == State.TRIANGLE)
            if len(tri):
                movers.append(tri)
                speeds.append(self._steer_triangles(step, tri))
        if self.strips is not None and self.strips.moving:
            moving, model = self._sensed_in(step, n_before, State.STRIP)
            if len(moving):
                length = self.strips.drive(moving, step.readings.of(moving, model), sw.models[model].sensor_range,
                                           sw.max_speed[moving] * self.dt)
                movers.append(moving)
                speeds.append(length / self.dt)
        if self.relocator is not None:
            moving, length = self._relocate(step, n_before)
            if len(moving):
                movers.append(moving)
                speeds.append(length / self.dt)
        if len(movers) == 1:
            return Command(agents, speed)
        return Command(np.concatenate(movers), np.concatenate(speeds))

    def _steer_triangles(self, step: StepInput, tri: np.ndarray) -> np.ndarray:
        """One go-to-goal step of the triangle routers ``tri`` (sensed this step); their speeds. Some settle."""
        sw = self.swarm
        model = int(sw.model[tri[0]])
        tri_scans = step.readings.of(tri, model)
        length, done = self.steering.steer(tri, sw.xy, sw.heading, tri_scans, sw.models[model].sensor_range,
                                           sw.max_speed[tri] * self.dt, self.r_eff)
        if not self.links_by_distance:  # the link test at settling (the module docstring)
            settle, lost = self.steering.check_links(tri, done, step.table, sw.xy)
            self.triangles_cut_off += int(np.count_nonzero(lost))
            done = settle | lost
        if done.any():
            sw.state[tri[done]] = State.TRIANGLE_SETTLED
            self.moving_triangles -= int(np.count_nonzero(done))
            self._nodes_changed()
        return length / self.dt

    def _sensed_in(self, step: StepInput, n_before: int, state: int) -> tuple[np.ndarray, int]:
        """Routers in ``state`` sensed this step (those that entered it this step move from the next); their model."""
        sw = self.swarm
        moving = np.flatnonzero(sw.state[:n_before] == state)
        if not len(moving):
            return moving, 0
        model = int(sw.model[moving[0]])
        sensed = step.readings.groups.get(model, (np.zeros(0, dtype=np.int64), None))[0]
        if len(sensed) == len(moving) and (sensed == moving).all():  # (the usual step: numpy.isin costs ~100 µs)
            return moving, model
        slot = np.minimum(np.searchsorted(sensed, moving), max(len(sensed) - 1, 0))  # (both ascending)
        return moving[sensed[slot] == moving] if len(sensed) else moving[:0], model

    def _relocate(self, step: StepInput, n_before: int) -> tuple[np.ndarray, np.ndarray]:
        """The relocation repair: start and stop relocations, steer the routers that relocate (sensed this step)."""
        assert self.relocator is not None
        sw = self.swarm
        started, stopped = self.relocator.update(step.t, step.table, sw)
        if len(started) or len(stopped):
            sw.state[started] = State.RELOCATING
            sw.state[stopped] = State.REFERENCE
            self._nodes_changed()
        moving, model = self._sensed_in(step, n_before, State.RELOCATING)
        if not len(moving):
            return moving, np.zeros(0)
        length, done = self.relocator.steer(moving, sw, step.readings.of(moving, model), sw.models[model].sensor_range,
                                            sw.max_speed[moving] * self.dt, self.r_eff)
        if done.any():  # arrived or blocked: it stays where it is and serves as a reference again
            sw.state[moving[done]] = State.REFERENCE
            self._nodes_changed()
        return moving, length
