"""The compiled steps: sense, decide and move of the batchable algorithms in one or two compiled passes.

The loop's step (:meth:`amronet.sim.loop.Loop.step`) calls the sense phase, the controller's ``decide`` and the move
phase one after another, each a handful of NumPy calls and compiled kernels. For a few dozen robots that glue, not
the work, is most of a step. A compiled step does the same three phases in compiled passes over the arrays (the
kernels are in :mod:`amronet.sim.step_kernels`):

* :class:`CompiledSpreading`, self-spreading with its paper rules (``walk: random``, ``stop_rule: distance``,
  ``triangle_rule: geometric``, every ``triangular`` mode). First every exploring router reads its row of the
  neighbour table (the reference tracking of :func:`~amronet.algorithms.references.track_row`) and, unless a
  triangular deployment may start this step (a router met a reference of another status, the two references are
  more than ``r_c`` apart and the local rule does not rule it out: then the controller's own Python code settles
  the explorers, :meth:`~amronet.algorithms.self_spreading.SelfSpreading.settle_explorers`), the routers about to
  lose their last reference stop. A kernel then draws the walkers' random numbers from the run's generator (or each
  from its run's generator in a batch) through the generators' C interface (:mod:`amronet.engine.bitgen`), in the
  order and number the controller draws them. Second, the routers still moving read
  their range rings (grid and bodies), steer (the random walk, :func:`~amronet.engine.motion.walk_one`, or the
  triangle router's go-to-goal, :func:`~amronet.algorithms.goto.steer_one`) and drive one after another with the
  collision checks (:func:`~amronet.engine.motion.drive_one`). With tens of thousands of movers
  (:func:`amronet.threads.use_threads`) the second pass is split in two: every mover's ring, decision and path
  against the map on several threads (:func:`~amronet.sim.step_kernels.sense_steer_plan_threaded`; they depend on
  where the robots stand before anybody moves and on the mover itself), then the collision checks against the
  bodies and the moves one after another (:func:`~amronet.sim.step_kernels.commit_moves`): the same numbers.
* :class:`CompiledField`, the potential field (every rule): the exploring routers' rings and obstacle forces, the
  controller's wake-and-accelerate kernel, the moves and its come-to-rest kernel, in one call (no random draws).

Agent-assisted runs have one of their own (:mod:`amronet.sim.compiled_agents`), listed here with the others.

Every per-robot computation is the same compiled function the phase-by-phase path calls, in the same order, so a run
gives the same result bit for bit with either step (the tests run both on the same seeds and compare;
``Loop(..., step="reference")`` selects the phase-by-phase path through the controllers' Python code, which stays
the readable reference). Runs with faults, and any other algorithm or rule, step phase by phase.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from amronet.algorithms.base import Readings, StepInput
from amronet.algorithms.potential_field import PotentialField
from amronet.algorithms.self_spreading import SelfSpreading
from amronet.engine.bitgen import draw_normal_uniform
from amronet.engine.robots import DEPLOYED_STATES, Role, state_lookup
from amronet.engine.streams import compiled_streams, normal_then_uniform
from amronet.sim.compiled_agents import CompiledAgents
from amronet.sim.step_kernels import (
    commit_moves,
    field_step,
    list_movers,
    sense_steer_drive,
    sense_steer_plan_threaded,
    track_explorers,
)
from amronet.sim.surroundings import Surroundings
from amronet.sim.swarm_stretch import SwarmStretch
from amronet.threads import LOCK, use_threads

if TYPE_CHECKING:
    from amronet.sim.loop import Loop

__all__ = ["COMPILED_STEPS", "CompiledField", "CompiledSpreading", "CompiledStep", "compiled_step_for"]


def _without_faults_or_agents(loop: Loop) -> bool:
    sc = loop.scenario
    return not sc.faults and sc.agents.per_base == 0 and not (loop.swarm.role == Role.AGENT).any()


class CompiledSpreading:
    """Sense, decide and move of a self-spreading loop in two compiled passes (see the module docstring).

    Args:
        loop: The loop whose phases it does; :meth:`applies` must hold.
    """

    def __init__(self, loop: Loop) -> None:
        c = loop.controller
        assert isinstance(c, SelfSpreading)
        sw = loop.swarm
        self.loop = loop
        self.controller = c
        n = len(sw)
        model = sw.models[c.router_model]
        self.around = Surroundings(loop, model, sw.role == Role.ROUTER)
        self.deployed_lookup = state_lookup(DEPLOYED_STATES)
        self.want_other = c.several_statuses and c.params.triangular != "off"
        self.local = c.params.triangular == "local"
        self.r_c = float(c.r_c)
        self.turn_sigma = float(c.walker.turn_sigma)
        self.is_ref = np.zeros(n, dtype=np.bool_)
        self.explorers = np.zeros(n, dtype=np.int64)
        self.new_current = np.zeros(n, dtype=np.int64)
        self.nearest = np.zeros(n)
        self.other = np.zeros(n, dtype=np.int64)
        self.movers = np.zeros(n, dtype=np.int64)
        self.walkers = np.zeros(n, dtype=np.int64)
        self.scans = np.zeros((n, model.sensor_beams))
        self.length = np.zeros(n)
        self.slot = np.zeros(n, dtype=np.int64)  # the threaded step's (large runs: amronet.threads)
        self.free = np.zeros(n, dtype=np.bool_)
        self.planned = np.zeros((n, 2))
        self.streams = compiled_streams(c.rng, n)
        """The draws' ``(bitgens, starts)`` (:mod:`amronet.engine.bitgen`), ``None``: numpy draws them."""
        self.normal = np.zeros(n)
        self.uniform = np.zeros(n)
        self.stretch = SwarmStretch(self) if SwarmStretch.applies(self) else None
        """The steps between records in one compiled call (:mod:`amronet.sim.swarm_stretch`), or ``None``."""

    @staticmethod
    def applies(loop: Loop) -> bool:
        """Whether the loop's phases are those this step compiles: self-spreading with its paper rules."""
        c = loop.controller
        if not isinstance(c, SelfSpreading) or not _without_faults_or_agents(loop):
            return False
        p = c.params
        sw = loop.swarm
        return (p.walk == "random" and p.stop_rule == "distance" and p.triangle_rule == "geometric"
                and c.needs_range_readings and bool(np.all(sw.model[sw.role == Role.ROUTER] == c.router_model)))

    def step(self) -> None:
        """Sense, decide and move once: what the loop's three phases and the controller do, bit for bit."""
        loop, c, sw, a = self.loop, self.controller, self.loop.swarm, self.around
        table = loop.table
        k, candidates, n_movers, n_walkers = track_explorers(
            sw.state, sw.status, c.current, self.deployed_lookup, self.is_ref, table.indptr, table.indices,
            table.dist, self.want_other, c.r_eff, sw.xy, self.r_c, self.local, c.disabled, self.explorers,
            self.new_current, self.nearest, self.other, self.movers, self.walkers)
        if candidates:  # a triangular deployment may start: the controller's own rules decide
            step = StepInput(loop.steps, loop.t, loop.dt, table, Readings({}))
            current = self.new_current[:k].copy()
            c.settle_explorers(step, self.explorers[:k].copy(), current, self.other[:k].copy(), current >= 0,
                               self.nearest[:k] >= c.r_eff)
            n_movers, n_walkers = list_movers(sw.state, self.movers, self.walkers)
        if n_movers == 0:
            c.refused[:] = False
            return
        normal, uniform = self.normal[:n_walkers], self.uniform[:n_walkers]
        if self.streams is None or not draw_normal_uniform(*self.streams, self.walkers[:n_walkers], normal, uniform):
            normal, uniform = normal_then_uniform(c.rng, self.walkers[:n_walkers])
        several, s_csr, drive_bodies, d_csr = a.bodies(sw.xy, table)
        movers = self.movers[:n_movers]
        s = c.steering
        if use_threads(n_movers):
            with LOCK:
                sense_steer_plan_threaded(
                    *a.grid, sw.xy, sw.heading, sw.state, sw.max_speed, sw.radius, c.refused, movers, normal, uniform,
                    self.turn_sigma, a.angles, a.sensor_range, *s_csr, several, s.goal, s.anchors, s.last_to_goal,
                    s.blocked_steps, s.give_up_steps, s.min_progress, c.r_eff, loop.dt, self.scans, self.length,
                    self.slot, self.free, self.planned)
            commit_moves(movers, self.length, self.free, self.planned, sw.xy, sw.radius, sw.state, s.goal,
                         sw.distance, c.refused, drive_bodies, *d_csr)
            return
        sense_steer_drive(*a.grid, sw.xy, sw.heading, sw.state, sw.max_speed, sw.radius, sw.distance, c.refused,
                          movers, normal, uniform, self.turn_sigma, a.angles, a.sensor_range, *s_csr, several, s.goal,
                          s.anchors, s.last_to_goal, s.blocked_steps, s.give_up_steps, s.min_progress, c.r_eff,
                          loop.dt, drive_bodies, *d_csr, self.scans, self.length)


class CompiledField:
    """Sense, decide and move of a potential-field loop in one compiled pass (:func:`.step_kernels.field_step`).

    The controller (:class:`~amronet.algorithms.potential_field.PotentialField`) already decides in one kernel and
    comes to rest in another; this step runs them with the range rings, the obstacle forces and the moves in one
    call, without random draws. Bit for bit the reference's result.

    Args:
        loop: The loop whose phases it does; :meth:`applies` must hold.
    """

    def __init__(self, loop: Loop) -> None:
        c = loop.controller
        assert isinstance(c, PotentialField)
        sw = loop.swarm
        self.loop, self.controller = loop, c
        routers = c.routers
        model = sw.models[int(sw.model[routers[0]])] if len(routers) else sw.models[0]
        self.around = Surroundings(loop, model, routers)
        self.scan = np.zeros(model.sensor_beams)
        self.movers = np.zeros(len(routers), dtype=np.int64)
        self.speed = np.zeros(len(routers))
        self.refused = np.zeros(len(routers), dtype=np.bool_)
        self.stretch = SwarmStretch(self) if SwarmStretch.applies(self) else None
        """The steps between records in one compiled call (:mod:`amronet.sim.swarm_stretch`), or ``None``."""

    @staticmethod
    def applies(loop: Loop) -> bool:
        """Whether the loop runs the potential field, without faults or agents, with one router model."""
        c = loop.controller
        return (isinstance(c, PotentialField) and _without_faults_or_agents(loop)
                and len(np.unique(loop.swarm.model[c.routers])) <= 1)

    def step(self) -> None:
        """Sense, decide and move once: what the loop's three phases and the controller do, bit for bit."""
        loop, c, sw, p, a = self.loop, self.controller, self.loop.swarm, self.controller.params, self.around
        table = loop.table
        sense = bool(c.needs_range_readings)
        several, s_csr, drive_bodies, d_csr = a.bodies(sw.xy, table, sense)
        field_step(*a.grid, c.routers, sw.state, sw.xy, sw.heading, sw.max_speed, sw.radius, sw.distance,
                   table.indptr, table.indices, table.dist, sense, a.angles, a.sensor_range, *s_csr,
                   several, float(c.k_obstacle), float(c.force_cap), c.obstacle_force, self.scan, c.velocity,
                   c.rest_count, c.window_start, c.force, c.held_force, float(c.k_cover), float(c.k_degree),
                   float(c.q_rc), int(p.connectivity_k), float(p.damping), float(p.mass), float(loop.dt),
                   float(p.rest_fraction), c.wakeups, int(p.rest_steps), drive_bodies, *d_csr, self.movers,
                   self.speed, self.refused)


CompiledStep = CompiledSpreading | CompiledField | CompiledAgents
"""A loop's compiled sense-decide-move."""

COMPILED_STEPS = (CompiledSpreading, CompiledField, CompiledAgents)
"""The compiled steps, each for the algorithm and rules its :meth:`applies` names."""


def compiled_step_for(loop: Loop) -> CompiledStep | None:
    """The compiled step that does the loop's sense, decide and move, or ``None`` (phase by phase)."""
    for kind in COMPILED_STEPS:
        if kind.applies(loop):
            return kind(loop)
    return None
