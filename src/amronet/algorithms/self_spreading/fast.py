"""Self-spreading's fast step: sense, decide and move in two compiled passes, and stretches of steps in one call.

The loop's step (:meth:`amronet.sim.loop.Loop.step`) calls the sense phase, the controller's ``decide`` and the move
phase one after another, each a handful of NumPy calls and compiled kernels. For a few dozen robots that glue, not
the work, is most of a step. :class:`CompiledSpreading` does the same three phases in compiled passes over the arrays
(the kernels are in :mod:`amronet.algorithms.self_spreading.kernels`), for self-spreading with every walk rule
(:mod:`~amronet.algorithms.self_spreading.walks`), both stop rules (``distance``, ``link-quality``), both triangle
rules and every ``triangular`` mode, with faults too; not with agents or the rules a policy outside commands.

First every exploring router reads its row of the neighbour table (the reference tracking of
:func:`~amronet.algorithms.common.references.track_row`) and, unless a triangular deployment may start this step (a
router met a reference of another status, the two references are more than ``r_c`` apart and the local rule does not
rule it out: then the controller's own Python code settles the explorers,
:meth:`~amronet.algorithms.self_spreading.controller.SelfSpreading.settle_explorers`), the routers about to lose their
last reference stop (under ``link-quality`` the rows' distances are the negated link margins, and the stop is the
smoothed margin's, :class:`~amronet.algorithms.common.link_quality.MarginSmoother`, as the controller's). A kernel
then draws the walkers' random numbers from the run's generator (or each from its run's
generator in a batch) through the generators' C interface (:mod:`amronet.engine.bitgen`), in the order and number the
controller draws them (every walk rule draws the random walk's two numbers per walker). Second, the routers still
moving read their range rings (grid and bodies), steer (the walk rule,
:func:`~amronet.algorithms.self_spreading.walk_kernels.walk_heading`, after the growth walks' field,
:func:`~amronet.algorithms.self_spreading.walk_kernels.growth_field_kernel`; or the triangle router's go-to-goal,
:func:`~amronet.algorithms.common.goto.steer_one`) and drive one after another with the collision checks
(:func:`~amronet.engine.motion.drive_one`). With tens of thousands of movers (:func:`amronet.threads.use_threads`) the
second pass is split in two: every mover's ring, decision and path against the map on several threads
(:func:`~amronet.algorithms.self_spreading.kernels.sense_steer_plan_threaded`), then the collision checks against the
bodies and the moves one after another (:func:`~amronet.algorithms.self_spreading.kernels.commit_moves`): the same
numbers.

Between two records the steps may be taken in a stretch (:class:`~amronet.algorithms.common.swarm_stretch.SwarmStretch`,
:func:`~amronet.algorithms.self_spreading.kernels.spreading_stretch`), which starts the triangular deployments of
the ``none`` and ``local`` rules itself (:mod:`~amronet.algorithms.self_spreading.triangle_kernels`) and stops before
a step in which one of the ``global`` rule may start (the ``link-quality`` stop rule takes no stretch: it reads the
margins of the radio's table, which the stretch's neighbour search does not give). The moves and rings read the
map's cells through one byte of flags each (:mod:`~amronet.algorithms.self_spreading.cells`). Every per-robot
computation is the same compiled function the phase-by-phase path calls, in the same order, so a run gives the
same result bit for bit with either step (``tests/test_compiled_step.py``).

Under a radio whose links are not decided by distance alone (walls, shadowing, packet loss), a triangle router settles
by the controller's link test (:meth:`~amronet.algorithms.common.goto.GoalSteering.check_links`), and under
``triangle_rule: link-quality`` it searches by its links' margins
(:class:`~amronet.algorithms.common.link_quality.MarginSearch`), neither of which the kernels do: while a triangle
router drives, and in a step in which a triangular deployment may start, the whole step is the loop's phases (the
range rings, the controller's ``decide``, the move), as the agent-assisted fast step does; so is a step in which one
may start under the ``link-quality`` stop rule.

In a run with faults the loop fails nodes before it calls :meth:`CompiledSpreading.step`, and offers stretches
where no fault is due within them and every fault's damage is repaired (:meth:`amronet.sim.loop.Loop.step`). A failed
node (state ``failed``) is neither settling nor
deployed, so the kernels do with it what the controller does, whatever it was doing when it failed (exploring,
driving to a triangle goal, a reference, a base station): it moves no more (no mover, so no speed to zero), tracks
and draws nothing, keeps its memory as it was and is nobody's reference (the table has no links of it either), but
its body stays where it is for the rings and the moves (the table's geometric view, which both paths read). The
steps the kernels leave to the phases (the controller's ``decide``) list no failed mover either: the same run
bit for bit (``tests/test_spreading_faults.py``). A stretch after a fault starts from the table's geometric view
and searches every pair within reach, failed nodes' links included, and the step :attr:`~CompiledSpreading.silences`
them all the same: every reader of its links filters them by state (the tracking's references and the growth field
are deployed nodes, a failed node's field is ``inf`` for the growth walks; the triangle kernels, the rings and moves
read no links but bodies; the books' settling rule reads states), so a failed node's links change nothing.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import replace
from typing import Any, Protocol

import numpy as np

from amronet.algorithms.base import Readings, StepInput
from amronet.algorithms.common.goto import steering_of
from amronet.algorithms.common.swarm_data import robots_of
from amronet.algorithms.common.swarm_stretch import SwarmStretch
from amronet.algorithms.common.swarm_stretch_kernels import Books, Radio
from amronet.algorithms.phases import move, sense
from amronet.algorithms.self_spreading.cells import Roomy, cell_flags
from amronet.algorithms.self_spreading.kernel_data import (
    Draws,
    Moves,
    SpreadingData,
    Streams,
    Tracked,
    Tracking,
    walk_of,
)
from amronet.algorithms.self_spreading.kernels import (
    commit_moves,
    list_movers,
    sense_steer_drive,
    sense_steer_drive_rules,
    sense_steer_plan_threaded,
    spreading_stretch,
    track_explorers,
)
from amronet.algorithms.self_spreading.walk_kernels import RANDOM
from amronet.algorithms.self_spreading.walks import WALKS
from amronet.algorithms.stepping import FastStep, StepContext, Stretched, Surroundings, Watch
from amronet.engine.bitgen import draw_normal_uniform
from amronet.engine.kernel_data import Csr
from amronet.engine.robots import DEPLOYED_STATES, Role, State, state_lookup
from amronet.engine.sensing import QuietRing
from amronet.engine.streams import compiled_streams, normal_then_uniform
from amronet.threads import LOCK, use_threads

__all__ = ["STOP_RULES", "CompiledSpreading", "SpreadingControls"]

STOP_RULES = ("distance", "link-quality")
"""The stop rules the kernels know (:func:`~amronet.algorithms.self_spreading.kernels.track_explorers`)."""


class SpreadingControls(Protocol):
    """What the fast step reads and keeps of its controller: nothing else of it.

    The controller is :class:`~amronet.algorithms.self_spreading.controller.SelfSpreading`: its names below are
    the declared interface between the two.
    """

    params: Any
    rng: Any
    r_c: float
    r_eff: float
    links_by_distance: bool
    router_model: int
    several_statuses: bool
    needs_range_readings: bool
    by_signal: bool
    searching: bool
    smoother: Any
    walker: Any
    current: np.ndarray
    disabled: np.ndarray
    refused: np.ndarray
    steering: Any
    settle_explorers: Callable[..., None]
    settling_rule: Callable[[], tuple[np.ndarray, np.ndarray]]
    decide: Callable[[StepInput], Any]
    after_move: Callable[[np.ndarray, np.ndarray], None]


class CompiledSpreading(FastStep):
    """Sense, decide and move of a self-spreading loop in two compiled passes (see the module docstring).

    Args:
        controller: The loop's controller.
        context: The loop's step context; :meth:`applies` must hold.
    """

    def __init__(self, controller: SpreadingControls, context: StepContext) -> None:
        c = controller
        sw = context.swarm
        self.swarm, self.controller, self.dt, self.omap = sw, c, context.dt, context.omap
        self.checks_links = not c.links_by_distance or c.searching
        """Whether triangle routers settle by the controller's link test or search by their links' margins (then
        their steps are the phases)."""
        self.by_signal = bool(c.by_signal)
        """The ``link-quality`` stop rule: the explorers track their references by link margin."""
        n = len(sw)
        model = sw.models[c.router_model]
        self.around = Surroundings(context, model, sw.role == Role.ROUTER)
        self.deployed_lookup = state_lookup(DEPLOYED_STATES)
        self.want_other = c.several_statuses and c.params.triangular != "off"
        self.local = c.params.triangular == "local"
        self.r_c = float(c.r_c)
        self.turn_sigma = float(c.walker.turn_sigma)
        self.random_walk = c.walker.rule == WALKS[RANDOM]
        """The paper's random walk: :func:`~amronet.algorithms.self_spreading.kernels.sense_steer_drive` (the other
        rules take :func:`~amronet.algorithms.self_spreading.kernels.sense_steer_drive_rules`)."""
        self.is_ref = np.zeros(n, dtype=np.bool_)
        self.explorers = np.zeros(n, dtype=np.int64)
        self.new_current = np.zeros(n, dtype=np.int64)
        self.nearest = np.zeros(n)
        self.other = np.zeros(n, dtype=np.int64)
        self.movers = np.zeros(n, dtype=np.int64)
        self.walkers = np.zeros(n, dtype=np.int64)
        self.started = np.zeros(n + 1, dtype=np.int64)
        self.triangles_started = 0
        """Triangular deployments started inside stretches (:mod:`.triangle_kernels`)."""
        self.scans = np.zeros((n, model.sensor_beams))
        self.length = np.zeros(n)
        self.slot = np.zeros(n, dtype=np.int64)  # the threaded step's (large runs: amronet.threads)
        self.free = np.zeros(n, dtype=np.bool_)
        self.planned = np.zeros((n, 2))
        streams = compiled_streams(c.rng, n)
        self.streams = None if streams is None else Streams(*streams)
        """The draws' generators (:mod:`amronet.engine.bitgen`), ``None``: numpy draws them."""
        self.normal = np.zeros(n)
        self.uniform = np.zeros(n)
        a = self.around
        routers = sw.role == Role.ROUTER
        roomy = Roomy(float(sw.max_speed[routers].max(initial=0.0)) * self.dt,
                      float(sw.radius[routers].max(initial=0.0)))  # the walkers' step and body (.cells)
        self.data = SpreadingData(
            a.grid, robots_of(sw), self._tracking(c),
            Tracked(self.explorers, self.new_current, self.nearest, self.other, self.movers, self.walkers,
                    self.started),
            walk_of(c.walker, c.refused), Draws(self.normal, self.uniform), steering_of(c.steering),
            QuietRing(a.angles, a.sensor_range, cell_flags(self.omap, a.grid, a.sensor_range, roomy)),
            Moves(self.scans, self.length, self.slot, self.free, self.planned, roomy),
            Csr(*a.no_bodies(n)), bool(a.collisions), float(self.dt))
        """What the kernels read and keep, built once: the arrays are the swarm's, the controller's and those above."""
        stretch = self.streams is not None and not self.by_signal and SwarmStretch.applies(context)
        self.stretcher = SwarmStretch(context, c.settling_rule(), self.around) if stretch else None
        """The steps between records in one compiled call (:mod:`amronet.algorithms.common.swarm_stretch`), or
        ``None`` (the walkers' draws go through numpy, the stop rule reads link margins the stretch's radio search
        does not give, or the stretch does not apply)."""
        self.stretches = self.stretcher is not None
        self.silences = self.stretches
        """Every stretch the step takes reads links only through its reference and growth lookups, which exclude a
        failed node (see the module docstring): it may take steps after nodes failed."""

    def _tracking(self, c: SpreadingControls) -> Tracking:
        """The kernels' reference tracking: the controller's arrays (and its link-quality stop rule's smoother)."""
        p, smoother = c.params, c.smoother
        smoothed, alpha = (np.zeros(0), 1.0) if smoother is None else (smoother.value, float(smoother.alpha))
        return Tracking(c.current, self.deployed_lookup, self.is_ref, bool(self.want_other), float(c.r_eff), self.r_c,
                        bool(self.local), c.disabled, self.by_signal, smoothed, alpha, float(p.stop_margin_db),
                        float(p.loss_margin_db), not self.checks_links and p.triangular in ("none", "local"))

    @staticmethod
    def applies(controller: SpreadingControls, context: StepContext) -> bool:
        """Whether the loop's phases are those this step compiles: no agents, one router model (faults or not).

        Every walk rule of :data:`~amronet.algorithms.self_spreading.walks.WALKS` and the stop rules of
        :data:`STOP_RULES` are compiled, with either triangle rule (the steps the kernels leave to the controller go
        through it); a rule commanded from outside is not.
        """
        c, p, sw = controller, controller.params, context.swarm
        if context.agents or p.walk not in WALKS or p.stop_rule not in STOP_RULES:
            return False
        return c.needs_range_readings and bool(np.all(sw.model[sw.role == Role.ROUTER] == c.router_model))

    def step(self, now: StepInput) -> None:
        """Sense, decide and move once: what the loop's three phases and the controller do, bit for bit."""
        c, sw, a = self.controller, self.swarm, self.around
        table = now.table
        if self.checks_links and (sw.state == State.TRIANGLE).any():
            self._phases(now)
            return
        # the link-quality stop rule tracks by signal: the rows' distances are the negated margins, as the
        # controller's (amronet.algorithms.common.link_quality.strongest_references)
        lengths = -np.asarray(table.margin, dtype=np.float64) if self.by_signal else table.dist
        k, candidates, n_movers, n_walkers = track_explorers(self.data, table.indptr, table.indices, lengths)
        if candidates and (self.checks_links or self.by_signal):  # (nothing changed yet) the controller's rules
            self._phases(now)
            return
        if candidates:  # a triangular deployment may start: the controller's own rules decide
            current = self.new_current[:k].copy()
            c.settle_explorers(replace(now, readings=Readings({})), self.explorers[:k].copy(), current,
                               self.other[:k].copy(), current >= 0, self.nearest[:k] >= c.r_eff)
            n_movers, n_walkers = list_movers(sw.state, self.movers, self.walkers)
        if n_movers == 0:
            c.refused[:] = False
            return
        normal, uniform = self.normal[:n_walkers], self.uniform[:n_walkers]
        if self.streams is None or not draw_normal_uniform(*self.streams, self.walkers[:n_walkers], normal, uniform):
            normal, uniform = normal_then_uniform(c.rng, self.walkers[:n_walkers])
        _, s_csr, drive_bodies, d_csr = a.bodies(sw.xy, table)
        if use_threads(n_movers):
            with LOCK:
                sense_steer_plan_threaded(self.data, n_movers, normal, uniform, *s_csr,
                                          (table.indptr, table.indices, table.dist), now.t)
            commit_moves(self.data, n_movers, *d_csr, drive_bodies)
            return
        if self.random_walk:  # the paper's walk: its own kernel, without the other rules' arguments
            sense_steer_drive(self.data, n_movers, normal, uniform, *s_csr, *d_csr)
            return
        sense_steer_drive_rules(self.data, n_movers, normal, uniform, *s_csr, *d_csr,
                                (table.indptr, table.indices, table.dist), now.t)

    def _phases(self, now: StepInput) -> None:
        """The loop's sense, decide and move phases for this step (as :meth:`~amronet.sim.loop.Loop.step` runs them)."""
        c, sw = self.controller, self.swarm
        command = c.decide(replace(now, readings=sense(c, sw, self.omap, now.table)))
        move(c, command, sw, self.omap, now.table, now.dt, self.around.collisions)

    def stretch(self, limit: int, now: StepInput, watch: Watch) -> Stretched | None:
        """Up to ``limit`` steps in one call (:func:`~amronet.algorithms.self_spreading.kernels.spreading_stretch`)."""
        if self.stretcher is None:
            return None
        if self.checks_links and (self.swarm.state == State.TRIANGLE).any():  # their steps are the phases
            return None
        index = now.index

        def kernel(limit: int, csr: Csr, radio: Radio, books: Books) -> tuple[int, int, Csr]:
            assert self.streams is not None
            return spreading_stretch(limit, self.data, self.streams, radio, csr, books, index)

        done = self.stretcher.take(limit, now.table, watch, kernel)
        count = int(self.started[0])
        if count:  # what GoalSteering.start sets besides the kernels' arrays: the link test's references
            who, steering = self.started[1:count + 1], self.controller.steering
            steering.refs[who] = steering.anchors[who]
            steering.heard_xy[who] = np.nan
            steering.retreating[who] = False
            self.started[0] = 0
            self.triangles_started += count
        return done
