"""The potential field's fast step: sense, decide and move in one compiled pass, and stretches of steps in one call.

The controller (:class:`~amronet.algorithms.potential_field.controller.PotentialField`) already decides in one kernel
and comes to rest in another; :class:`CompiledField` runs them with the range rings, the obstacle forces and the moves
in one call (:func:`~amronet.algorithms.potential_field.kernels.field_step`), without random draws, and the steps
between two records in one call (:func:`~amronet.algorithms.potential_field.kernels.field_stretch`, through
:class:`~amronet.algorithms.common.swarm_stretch.SwarmStretch`; in a run with faults, until the first node fails: a
router's force counts every neighbour the stretch's search finds, a failed one too, where the table has silenced it).
Bit for bit the reference's result.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from amronet.algorithms.common.swarm_data import Ring, robots_of
from amronet.algorithms.common.swarm_stretch import SwarmStretch
from amronet.algorithms.common.swarm_stretch_kernels import Books, Radio
from amronet.algorithms.potential_field.kernel_data import (
    FieldControls,
    FieldData,
    FieldScratch,
    field_constants_of,
    field_state_of,
)
from amronet.algorithms.potential_field.kernels import field_step, field_stretch
from amronet.algorithms.stepping import FastStep, StepContext, Stretched, Surroundings, Watch
from amronet.engine.kernel_data import Csr

if TYPE_CHECKING:
    from amronet.algorithms.base import StepInput

__all__ = ["CompiledField", "FieldControls"]


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
        a = self.around
        self.data = FieldData(
            a.grid, robots_of(sw), c.routers, Ring(a.angles, a.sensor_range), field_state_of(c),
            field_constants_of(c, self.dt), FieldScratch(self.scan, self.movers, self.speed, self.refused),
            Csr(*a.no_bodies(len(sw))), bool(a.collisions), bool(c.needs_range_readings))
        """What the kernels read and keep, built once: the arrays are the swarm's, the controller's and those above."""
        self.stretcher = (SwarmStretch(context, c.settling_rule(), self.around) if SwarmStretch.applies(context)
                          else None)
        """The steps between records in one compiled call (:mod:`amronet.algorithms.common.swarm_stretch`), or
        ``None``."""
        self.stretches = self.stretcher is not None

    @staticmethod
    def applies(controller: FieldControls, context: StepContext) -> bool:
        """Whether the loop runs the potential field without agents, with one router model (faults or not).

        A failed router (state ``failed``) is neither exploring nor resting: the kernels, as the controller's, never
        sense, wake or move it (``tests/test_spreading_faults.py``).
        """
        if context.agents:
            return False
        return len(np.unique(context.swarm.model[controller.routers])) <= 1

    def step(self, now: StepInput) -> None:
        """Sense, decide and move once: what the loop's three phases and the controller do, bit for bit."""
        c, sw, a = self.controller, self.swarm, self.around
        table = now.table
        several, s_csr, drive_bodies, d_csr = a.bodies(sw.xy, table, bool(c.needs_range_readings))
        field_step(self.data, table.indptr, table.indices, table.dist, *s_csr, several, *d_csr, drive_bodies)

    def stretch(self, limit: int, now: StepInput, watch: Watch) -> Stretched | None:
        """Up to ``limit`` steps in one call (:func:`~amronet.algorithms.potential_field.kernels.field_stretch`)."""
        if self.stretcher is None:
            return None
        return self.stretcher.take(limit, now.table, watch, self._kernel)

    def _kernel(self, limit: int, csr: Csr, radio: Radio, books: Books) -> tuple[int, int, Csr]:
        return field_stretch(limit, self.data, radio, csr, books)
