"""Stretches of self-spreading and potential-field loops: the steps between two records in one compiled call.

With a few dozen robots per run, a step of a self-spreading or potential-field batch is mostly Python between its
kernels: the compiled step's glue (:mod:`amronet.sim.compiled_step`), the radio medium's table, the loop's books.
:class:`SwarmStretch` hands the steps up to the next recorded one to the kernels of
:mod:`amronet.sim.swarm_stretch_kernels`, which take them one after another with the same kernels on the same numbers
(the walkers' draws too, through :mod:`amronet.engine.bitgen`), so every run's result is the same bit for bit
(``tests/test_swarm_stretch.py``).

A stretch runs only where its steps need nothing else: a radio that keeps every pair within its reach (the unit
disk), rings and moves that reach no farther than the table, one thread. It stops after a step that changed whether an
active run is settled, and before a self-spreading step in which a triangular deployment may start.
"""

from __future__ import annotations

import time
from typing import TYPE_CHECKING

import numpy as np

from amronet.engine.neighbours import GroupIds
from amronet.sim.swarm_stretch_kernels import (
    BAD_DRAW,
    CANDIDATES,
    NON_FINITE,
    SETTLING,
    field_stretch,
    spreading_stretch,
)
from amronet.threads import use_threads

if TYPE_CHECKING:
    from amronet.sim.compiled_step import CompiledField, CompiledSpreading

__all__ = ["SwarmStretch"]


class SwarmStretch:
    """Steps of a :class:`~amronet.sim.compiled_step.CompiledSpreading` or ``CompiledField`` loop in one call.

    Args:
        compiled: The loop's compiled step; :meth:`applies` must hold.
    """

    def __init__(self, compiled: CompiledSpreading | CompiledField) -> None:
        from amronet.sim.compiled_step import CompiledSpreading

        self.compiled = compiled
        loop = compiled.loop
        self.spreading = isinstance(compiled, CompiledSpreading)
        ids = GroupIds.of(loop.groups, len(loop.swarm))
        self.radio = (float(loop.medium.reach), ids.ids, int(ids.count))
        self.groups = ids.ids
        self.n_runs = int(ids.count)
        self.settling = compiled.controller.settling_rule()  # (robots are never added: fixed for the loop)
        self.counts = np.zeros(self.n_runs, dtype=np.int64)
        self.steps = 0
        """Steps taken in stretches."""
        self.ends = {"quiet": 0, "settling": 0, "candidates": 0}
        """How many stretches ended each way: all steps taken, a run's settled state changed, a triangle may start."""

    @staticmethod
    def applies(compiled: CompiledSpreading | CompiledField) -> bool:
        """Whether the steps can be taken in stretches: a radio that keeps every pair, one thread, compiled draws."""
        from amronet.sim.compiled_step import CompiledSpreading

        loop = compiled.loop
        draws = not isinstance(compiled, CompiledSpreading) or compiled.streams is not None  # (walkers draw in it)
        return loop.medium.keeps_every_pair and not use_threads(len(loop.swarm)) and draws

    def run(self, limit: int, active: np.ndarray, settled: np.ndarray) -> int:
        """Take up to ``limit`` steps, none of them recorded; how many were taken (0: none could be).

        Args:
            limit: Most steps to take.
            active: Indices of the runs still running.
            settled: Per run, whether it is settled now (the loop's books after the last step).

        Raises:
            ValueError: A robot's position became non-finite (what the radio's table refuses).
        """
        comp = self.compiled
        loop, a = comp.loop, comp.around
        sw, table = loop.swarm, loop.table
        n = len(sw)
        beyond = a.sense_reach > table.r or (a.collisions and a.drive_reach > table.r)
        if table.candidates is not None or n < 2 or beyond:
            return 0
        on = np.zeros(self.n_runs, dtype=np.bool_)
        on[active] = True
        watch = (*self.settling, self.groups, on, np.asarray(settled, dtype=np.bool_), self.counts)
        csr = (table.indptr, table.indices, table.dist)
        start = time.perf_counter()
        kernel_args = self._spreading(limit, csr, watch) if self.spreading else self._field(limit, csr, watch)
        done, how, indptr, indices, dist = kernel_args
        loop.steps += done
        self.steps += done
        if done:
            loop.table = loop.medium.plain_table(sw.xy.copy(), indptr, indices, dist, loop.groups)
        loop.phase_seconds["sense+decide+move"] += time.perf_counter() - start
        if how == NON_FINITE:
            raise ValueError("xy has non-finite coordinates")
        if how == BAD_DRAW:
            raise AssertionError("the walkers were not listed in order")
        self.ends[{SETTLING: "settling", CANDIDATES: "candidates"}.get(how, "quiet")] += 1
        return done

    def _spreading(self, limit: int, csr: tuple, watch: tuple) -> tuple:
        comp = self.compiled
        loop, c, a, sw = comp.loop, comp.controller, comp.around, comp.loop.swarm
        s = c.steering
        n = len(sw)
        track = (c.current, comp.deployed_lookup, comp.is_ref, bool(comp.want_other), float(c.r_eff), comp.r_c,
                 bool(comp.local), c.disabled, comp.explorers, comp.new_current, comp.nearest, comp.other, comp.movers,
                 comp.walkers)
        draws = (*comp.streams, comp.normal, comp.uniform)
        steer = (c.refused, comp.turn_sigma, a.angles, a.sensor_range, True, s.goal, s.anchors, s.last_to_goal,
                 s.blocked_steps, int(s.give_up_steps), float(s.min_progress), float(loop.dt), bool(a.collisions),
                 *a.no_bodies(n), comp.scans, comp.length)
        robots = (sw.xy, sw.heading, sw.state, sw.status, sw.max_speed, sw.radius, sw.distance)
        return spreading_stretch(limit, a.grid, robots, track, draws, steer, self.radio, csr, watch)

    def _field(self, limit: int, csr: tuple, watch: tuple) -> tuple:
        comp = self.compiled
        loop, c, a, sw = comp.loop, comp.controller, comp.around, comp.loop.swarm
        p = c.params
        n = len(sw)
        sense = bool(c.needs_range_readings)
        head = (*a.grid, c.routers, sw.state, sw.xy, sw.heading, sw.max_speed, sw.radius, sw.distance)
        tail = (*a.no_bodies(n), sense, True, float(c.k_obstacle), float(c.force_cap), c.obstacle_force,
                comp.scan, c.velocity, c.rest_count, c.window_start, c.force, c.held_force, float(c.k_cover),
                float(c.k_degree), float(c.q_rc), int(p.connectivity_k), float(p.damping), float(p.mass),
                float(loop.dt), float(p.rest_fraction), c.wakeups, int(p.rest_steps), bool(a.collisions), comp.movers,
                comp.speed, comp.refused)
        return field_stretch(limit, head, (a.angles, a.sensor_range), tail, sense, bool(a.collisions), self.radio,
                             csr, watch)
