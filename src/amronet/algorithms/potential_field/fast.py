"""The potential field's fast step: sense, decide and move in one compiled pass, and stretches of steps in one call.

The controller (:class:`~amronet.algorithms.potential_field.controller.PotentialField`) already decides in one kernel
and comes to rest in another; :class:`CompiledField` runs them with the range rings, the obstacle forces and the moves
in one call (:func:`~amronet.algorithms.potential_field.kernels.field_step`), without random draws, and the steps
between two records in one call (:func:`~amronet.algorithms.potential_field.kernels.field_stretch`, through
:class:`~amronet.algorithms.common.swarm_stretch.SwarmStretch`). Bit for bit the reference's result.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING, Any, Protocol

import numpy as np

from amronet.algorithms.common.swarm_stretch import SwarmStretch
from amronet.algorithms.potential_field.kernels import field_step, field_stretch
from amronet.algorithms.stepping import FastStep, StepContext, Stretched, Surroundings, Watch

if TYPE_CHECKING:
    from amronet.algorithms.base import StepInput

__all__ = ["CompiledField", "FieldControls"]


class FieldControls(Protocol):
    """What the fast step reads and keeps of its controller: nothing else of it.

    The controller is :class:`~amronet.algorithms.potential_field.controller.PotentialField`: its names below are
    the declared interface between the two.
    """

    params: Any
    routers: np.ndarray
    needs_range_readings: bool
    k_obstacle: float
    force_cap: float
    k_cover: float
    k_degree: float
    q_rc: float
    obstacle_force: np.ndarray
    velocity: np.ndarray
    rest_count: np.ndarray
    window_start: np.ndarray
    force: np.ndarray
    held_force: np.ndarray
    wakeups: np.ndarray
    settling_rule: Callable[[], tuple[np.ndarray, np.ndarray]]


class CompiledField(FastStep):
    """Sense, decide and move of a potential-field loop in one compiled pass (see the module docstring).

    Args:
        controller: The loop's controller.
        context: The loop's step context; :meth:`applies` must hold.
    """

    def __init__(self, controller: FieldControls, context: StepContext) -> None:
        c = controller
        sw = context.swarm
        self.swarm, self.controller, self.dt = sw, c, context.dt
        routers = c.routers
        model = sw.models[int(sw.model[routers[0]])] if len(routers) else sw.models[0]
        self.around = Surroundings(context, model, routers)
        self.scan = np.zeros(model.sensor_beams)
        self.movers = np.zeros(len(routers), dtype=np.int64)
        self.speed = np.zeros(len(routers))
        self.refused = np.zeros(len(routers), dtype=np.bool_)
        self.stretcher = (SwarmStretch(context, c.settling_rule(), self.around) if SwarmStretch.applies(context)
                          else None)
        """The steps between records in one compiled call (:mod:`amronet.algorithms.common.swarm_stretch`), or
        ``None``."""
        self.stretches = self.stretcher is not None

    @staticmethod
    def applies(controller: FieldControls, context: StepContext) -> bool:
        """Whether the loop runs the potential field without faults or agents, with one router model."""
        if context.faults or context.agents:
            return False
        return len(np.unique(context.swarm.model[controller.routers])) <= 1

    def step(self, now: StepInput) -> None:
        """Sense, decide and move once: what the loop's three phases and the controller do, bit for bit."""
        c, sw, p, a = self.controller, self.swarm, self.controller.params, self.around
        table = now.table
        sense = bool(c.needs_range_readings)
        several, s_csr, drive_bodies, d_csr = a.bodies(sw.xy, table, sense)
        field_step(*a.grid, c.routers, sw.state, sw.xy, sw.heading, sw.max_speed, sw.radius, sw.distance,
                   table.indptr, table.indices, table.dist, sense, a.angles, a.sensor_range, *s_csr,
                   several, float(c.k_obstacle), float(c.force_cap), c.obstacle_force, self.scan, c.velocity,
                   c.rest_count, c.window_start, c.force, c.held_force, float(c.k_cover), float(c.k_degree),
                   float(c.q_rc), int(p.connectivity_k), float(p.damping), float(p.mass), float(self.dt),
                   float(p.rest_fraction), c.wakeups, int(p.rest_steps), drive_bodies, *d_csr, self.movers,
                   self.speed, self.refused)

    def stretch(self, limit: int, now: StepInput, watch: Watch) -> Stretched | None:
        """Up to ``limit`` steps in one call (:func:`~amronet.algorithms.potential_field.kernels.field_stretch`)."""
        if self.stretcher is None:
            return None
        return self.stretcher.take(limit, now.table, watch, self._kernel)

    def _kernel(self, limit: int, csr: tuple, radio: tuple, books: tuple) -> tuple:
        c, a, sw = self.controller, self.around, self.swarm
        p = c.params
        n = len(sw)
        sense = bool(c.needs_range_readings)
        head = (*a.grid, c.routers, sw.state, sw.xy, sw.heading, sw.max_speed, sw.radius, sw.distance)
        tail = (*a.no_bodies(n), sense, True, float(c.k_obstacle), float(c.force_cap), c.obstacle_force,
                self.scan, c.velocity, c.rest_count, c.window_start, c.force, c.held_force, float(c.k_cover),
                float(c.k_degree), float(c.q_rc), int(p.connectivity_k), float(p.damping), float(p.mass),
                float(self.dt), float(p.rest_fraction), c.wakeups, int(p.rest_steps), bool(a.collisions),
                self.movers, self.speed, self.refused)
        return field_stretch(limit, head, (a.angles, a.sensor_range), tail, sense, bool(a.collisions), radio, csr,
                             books)
