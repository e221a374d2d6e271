"""Quiet stretches of an agent-assisted run: the steps between two records in one compiled call while nothing happens.

Most steps of an agent-assisted run with the frontier explorer are *quiet*: no agent has to act, every agent
follows its plan, and only the agents move. With a few agents such a step is mostly Python between a dozen small
calls (the compiled step's three kernels, the explorer's inputs, the radio's table, the agents' connection).
:class:`QuietStretch` hands the loop's steps up to the next recorded one to
:func:`~amronet.algorithms.agent_assisted.stretch_kernels.quiet_stretch`, which does them one after another with the
same compiled
functions, and finishes in Python the step at which it stopped, if any, the way
:class:`~amronet.algorithms.agent_assisted.fast.CompiledAgents` does it. The explorer's fresh headings and the random
walk of the agents without a plan are drawn in the kernel from the run's generator itself
(:mod:`amronet.engine.bitgen`), number for number in the order the explorer draws them, so every run's numbers stay
the same bit for bit (``tests/test_agent_stretch.py``). The kernel builds the radio's tables itself, as the radio does
(:mod:`.stretch_links`): under the unit disk and the built-in path-loss law, walls and shadowing too
(``tests/test_agent_stretch_radio.py``).

Once nodes have failed the loop offers stretches while every fault's damage is repaired and none is due, with the
failed nodes (:attr:`~amronet.algorithms.stepping.Watch.silent`): the stretch starts from the table that has lost
their links and its geometric view, and the kernel drops their links from every table it builds, as the radio does
(:func:`~.stretch_links.next_radio`), so the agents' tracking, the drop rules, their connection books and the repair
read the links the step-by-step path reads (``tests/test_compiled_repair.py``).
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numpy as np

from amronet.algorithms.agent_assisted.rule_check import paper_rule_step
from amronet.algorithms.agent_assisted.stretch_books import ReverseDrop, no_retracing, no_reverse_drop
from amronet.algorithms.agent_assisted.stretch_kernels import (
    ACTS,
    LINKED,
    NON_FINITE,
    TRIANGLES_END,
    quiet_stretch,
)
from amronet.algorithms.agent_assisted.stretch_links import NO_MARGIN, Radio
from amronet.algorithms.agent_assisted.stretch_tuples import Frontier, Moves, Moving, Triangles
from amronet.algorithms.stepping import RESTORING_AGENTS, AgentBooks, StepContext, Stretched
from amronet.engine import bitgen
from amronet.engine.hearing import HearingInputs
from amronet.engine.robots import State
from amronet.engine.sensing import beam_angles
from amronet.threads import use_threads

if TYPE_CHECKING:
    from amronet.algorithms.agent_assisted.fast import CompiledAgents
    from amronet.algorithms.base import StepInput
    from amronet.engine.table import NeighbourTable

__all__ = ["QuietStretch"]

_NO_ROBOTS = np.zeros(0, dtype=np.int64)
_NO_STEPS = np.zeros(0)
_NONE_SILENT = np.zeros(0, dtype=np.bool_)
_NO_LINKS = np.zeros(0, dtype=np.int64)
_ONE_BEAM = beam_angles(1)  # (read-only)



class QuietStretch:
    """Steps of a :class:`~amronet.algorithms.agent_assisted.fast.CompiledAgents` loop done in one compiled call.

    Args:
        compiled: The loop's compiled step; :meth:`applies` must hold.
    """

    def __init__(self, compiled: CompiledAgents, context: StepContext) -> None:
        self.compiled = compiled
        self.radio_reach = float(context.radio_reach)
        self.hearing = context.link_inputs
        """The radio's inputs as the stretch builds its tables (:mod:`.stretch_links`)."""
        h = None if self.hearing is None else HearingInputs(*self.hearing)
        self.laws = h is not None and (h.wall_db > 0.0 or h.clip > 0.0)
        """Whether the links are decided by their margins (walls or shadowing)."""
        self.ends = {"quiet": 0, "acts": 0, "triangle": 0, "linked": 0}
        """How many stretches ended each way: all steps quiet, an agent acting, a triangle or strip router arriving or
        giving up, every agent linked (a fault's damage repaired,
        :data:`~amronet.algorithms.stepping.RESTORING_AGENTS`)."""
        self.idle_steps = 0
        """Steps taken in stretches in which an agent without a plan walked at random."""
        self._bitgen: tuple[object, int] | None = None
        """The run's generator and its bit generator's address (:func:`amronet.engine.bitgen.addresses`)."""
        self.triangles_looked_at = 0
        """Steps taken in stretches in which an agent heard another network's reference and no triangle went ahead."""
        self.triangle_steps = 0
        """Steps taken in stretches with triangle routers driving to their goals."""
        self.strip_steps = 0
        """Steps taken in stretches with strip routers driving to their goals (``strip-goals``)."""
        self.backing_steps = 0
        """Steps taken in stretches that began with an agent backing up (``agents.reverse_drop``)."""
        self.paper = paper_rule_step(context.dt)
        """The drop rule's check under the paper's rule alone (none)."""
        self.no_retracing = no_retracing(len(compiled.controller.agents))
        """The kernel's :class:`~.stretch_books.Retracing` without ``repair: retrace``."""
        self.no_reverse_drop = no_reverse_drop(len(compiled.controller.agents))
        """The kernel's :class:`~.stretch_books.ReverseDrop` without ``agents.reverse_drop``."""

    def _moving(self, length: np.ndarray, r: float) -> Moving | None:
        """The kernel's :class:`~.stretch_tuples.Moving`: the triangle and strip routers driving to their goals.

        The triangle routers, then the strip routers (the order in which ``movers_command`` moves them), each kind
        with the ``r_keep`` it steers with (:meth:`.strip_driving.StripDrivers.drive`: the rule's keep radius); or
        the relocating routers with the repair's steering, where the repair lets them move in the stretch
        (:attr:`.repair_step.RepairStep.watch`).
        ``None`` when their steps cannot be taken in the stretch: routers of several models, or of the agents' model,
        or whose rings or moves reach beyond the radio's table (the sense and move phases would search anew).
        """
        comp = self.compiled
        c, sw, a = comp.controller, comp.swarm, comp.around
        steering = c.steering
        strips_moving = c.strips is not None and c.strips.moving
        largest = a.largest_radius()
        watch = None if comp.repair is None else comp.repair.watch
        if not c.moving_triangles and not strips_moving and watch is None:  # (most calls: no router drives)
            return Moving(_NO_ROBOTS, _ONE_BEAM, 0.0, _NO_STEPS, steering.goal, steering.anchors,
                          steering.last_to_goal, steering.blocked_steps, int(steering.give_up_steps),
                          float(steering.min_progress), _NO_STEPS, float(c.dt), largest, steering.refs,
                          steering.heard_xy, 0, _NONE_SILENT, _NO_LINKS)
        tri = np.flatnonzero(sw.state == State.TRIANGLE) if c.moving_triangles else _NO_ROBOTS
        keep = np.full(len(tri), float(c.r_eff))
        tested = 0 if c.links_by_distance else len(tri)  # (the link test at settling: .movers)
        network, links = _NONE_SILENT, _NO_LINKS
        if watch is not None:  # (no triangle or strip router drives then)
            tri, steering, network, links = watch.routers, watch.steering, watch.network, watch.links
            keep = np.full(len(tri), float(c.r_eff))
        if strips_moving:
            assert c.strips is not None
            strips = np.flatnonzero(sw.state == State.STRIP)
            tri = np.concatenate([tri, strips])
            keep = np.concatenate([keep, np.full(len(strips), float(c.strips.rule.keep_radius()))])
        steer = (steering.goal, steering.anchors, steering.last_to_goal, steering.blocked_steps,
                 int(steering.give_up_steps), float(steering.min_progress), keep, float(c.dt), largest,
                 steering.refs, steering.heard_xy, tested, network, links)
        if len(tri) == 0:
            return Moving(_NO_ROBOTS, _ONE_BEAM, 0.0, _NO_STEPS, *steer)
        model = int(sw.model[tri[0]])
        if model == c.agent_model or (sw.model[tri] != model).any():
            return None
        spec = sw.models[model]
        max_step = sw.max_speed[tri] * c.dt
        # (the step a router takes, turned into the command's speed and back, may exceed max_step by a rounding)
        reach = 2.0 * largest + 2.0 * max(max(length.tolist()), float(max_step.max()) * (1.0 + 1e-9))
        if spec.sensor_range + largest > r or (a.collisions and reach > r):
            return None
        return Moving(tri, beam_angles(spec.sensor_beams), float(spec.sensor_range), max_step, *steer)

    @staticmethod
    def applies(compiled: CompiledAgents, context: StepContext) -> bool:
        """Whether the loop's steps can be taken in stretches.

        The frontier explorer, a radio whose tables the stretch can build (the unit disk, the built-in path-loss
        law: :attr:`~amronet.algorithms.stepping.StepContext.link_inputs`), a drop rule the kernel checks (the
        paper's, or one where :attr:`.rule_check.RuleCheck.stretches`), and draws in compiled code
        (:data:`amronet.engine.bitgen.AVAILABLE`).
        """
        rules = compiled.rules
        return (bitgen.AVAILABLE and compiled.frontier and context.link_inputs is not None
                and (rules is None or rules.stretches))

    def take(self, limit: int, now: StepInput, agent_books: AgentBooks, silent: np.ndarray | None = None,
             restoring: int = 0) -> Stretched | None:
        """Take up to ``limit`` steps (at least one), none of them recorded; ``None`` where none can be taken.

        A stretch starts only where a quiet step may: no router settling, the agents' and the triangle and strip
        routers' readings and moves within the radio's table, the explorer's deployed nodes painted.
        Agents without a plan walk at random in it. The step at which the kernel stops (an agent acts, a triangle or
        strip router arrives or gives up) is left for the loop to finish
        (:attr:`~amronet.algorithms.stepping.Stretched.finish`).
        The agents' connection books are kept in ``agent_books``'s arrays, step by step; the loop closes them.
        ``silent``: the failed nodes (:attr:`~amronet.algorithms.stepping.Watch.silent`), whose links the kernel drops.
        ``restoring``: a fault's damage is not repaired yet (:attr:`~amronet.algorithms.stepping.Watch.restoring`):
        no triangle router may drive, and under ``RESTORING_AGENTS`` the kernel stops after the first step at whose
        end every agent has a path to a base station (the faults' books look then).
        """
        comp = self.compiled
        c, explorer, a = comp.controller, comp.explorer, comp.around
        sw, table = comp.swarm, now.table
        n = len(sw)
        dropped = table.candidates is not None and not self.laws and silent is None  # (links lost at random)
        if c.settle_at or n < 2 or use_threads(n) or dropped:
            return None
        reverse = self._reverse_drop(limit)
        if reverse is None:  # (the retrace repair's agents back up their own way)
            return None
        backing = bool(c.reversing.any())
        start = (self.no_retracing, limit) if comp.repair is None else comp.repair.stretch_start(now, limit)
        if start is None:  # (the repair is not idle, or an agent backs up now)
            return None
        retracing, limit = start
        length, reach = comp.moves()
        farthest, widest = length, reach
        if retracing.backing.any():  # (retrace's backing agents go up to their top speed)
            farthest = np.where(retracing.backing, retracing.max_step * (1.0 + 1e-9), length)
            widest = max(reach, 2.0 * a.largest_radius() + 2.0 * float(farthest.max()))
        if a.sensor_range + a.largest_radius() > table.r or (a.collisions and widest > table.r):
            return None
        moving = self._moving(farthest, table.r)
        if moving is None:
            return None
        tri = moving.tri
        if restoring and len(tri) and not len(moving.network):  # (watched: RepairStep.relocating_start)
            return None  # (a relay on its way could give a cut-off router its path back, or take it)
        m = len(c.agents)
        is_ref, deployed_xy = c.deployed_nodes()
        inputs = explorer.navigation_inputs(a.sensor_range, m, deployed_xy)
        if inputs is None:
            return None
        avoid, layers, settings, plans, buffers = inputs
        grid = comp.knowledge
        knowledge = comp.knowledge_for(deployed_xy, a.sensor_range)
        # every structure as a plain tuple (see .kernels)
        # (its RandomExplorer's, as it scales the noise; math.sqrt and np.sqrt both round correctly: the same number)
        sigma = float(explorer.turn_noise * math.sqrt(explorer.dt))
        frontier = Frontier(explorer.steps, grid.stamp, avoid, self._address(c.rng), sigma, *layers, settings, plans,
                            buffers, explorer.plans.active)
        triangles = Triangles(comp.triangle_rule, float(c.r_c), c.disabled, c.served_pairs())
        rules = self.paper if comp.rules is None else comp.rules.in_stretch(now.index, now.dt)
        moves = Moves(c.agents, length, reach, a.collisions, tuple(retracing), tuple(reverse),
                      restoring == RESTORING_AGENTS)
        done, how, n_cand, n_losing, radio, scans, grid.stamp, explorer.steps, looked, idle = quiet_stretch(
            comp.grid, comp.robots(), comp.ring, tuple(moves),
            self._radio(table, comp.rules is not None and comp.rules.reads_margins, silent), comp.tracking(is_ref),
            (tuple(triangles), tuple(rules)), tuple(moving), knowledge, tuple(frontier), tuple(agent_books), limit)
        if comp.repair is not None:
            comp.repair.stretch_end(done, retracing)
        if how == NON_FINITE:
            return Stretched(done, non_finite=True)
        csr = (radio[5], radio[6], radio[7]) if done else None  # the pairs searched, and their margins
        margin = radio[9] if done and self.laws else None
        self.ends[{ACTS: "acts", TRIANGLES_END: "triangle", LINKED: "linked"}.get(how, "quiet")] += 1
        self.idle_steps += idle
        if backing:
            self.backing_steps += done
        self.triangles_looked_at += looked
        if len(tri):
            driving = sw.state[tri]
            self.triangle_steps += done if (driving == State.TRIANGLE).any() else 0
            self.strip_steps += done if (driving == State.STRIP).any() else 0
        if how not in (ACTS, TRIANGLES_END):
            return Stretched(done, csr, margin=margin)
        # stopped part-way through a step, the generator as the step-by-step path leaves it there: the loop finishes it

        def finish(step: StepInput) -> None:
            readings = comp.readings(step, scans, np.sort(tri))  # (ascending, as the sense phase has them)
            if how == ACTS:
                comp.act(step, n, n_cand, n_losing, scans, readings)
                return
            if len(tri):
                comp.finish(step, n, readings)
            else:
                comp.drive(step)

        return Stretched(done, csr, finish=finish, margin=margin)

    def _reverse_drop(self, limit: int) -> ReverseDrop | None:
        """The kernel's :class:`~.stretch_books.ReverseDrop` for up to ``limit`` steps; ``None``: no stretch now.

        None under ``repair: retrace`` (its agents back up their own way), nor where an agent's path could reach its
        most points in the stretch (:class:`~.drops.trail.Trails`: the oldest would go).
        """
        comp = self.compiled
        c = comp.controller
        trails = c.trails
        if trails is None:
            return self.no_reverse_drop
        if (comp.repair is not None and comp.repair.retracer is not None) or not trails.reserve(limit):
            return None
        return ReverseDrop(trails.points, trails.count, trails.last, float(trails.spacing), c.contact_since,
                           float(c.reverse_after_s), c.reversing)

    def _address(self, rng: np.random.Generator) -> int:
        """The ``bitgen_t`` address of ``rng``'s bit generator (kept while it is the run's generator)."""
        if self._bitgen is None or self._bitgen[0] is not rng:
            self._bitgen = (rng, int(bitgen.addresses([rng])[0]))
        return self._bitgen[1]

    def _radio(self, table: NeighbourTable, margins: bool, silent: np.ndarray | None) -> tuple:
        """The kernel's :class:`~.stretch_links.Radio` of this step's ``table`` (``margins``: the rule reads them).

        ``table`` has lost the ``silent`` nodes' links (its geometric view has them). Margins of the links' lengths
        alone (no walls, no shadowing) the kernel takes of the lengths (:func:`~.stretch_links.margin_law`).
        """
        near = table.geometric
        assert self.hearing is not None  # (applies)
        margin = table.margin if margins and self.laws else NO_MARGIN
        return tuple(Radio(self.radio_reach, table.indptr, table.indices, table.dist, margin, near.indptr, near.indices,
                           near.dist, near.xy, near.link_margin if self.laws else NO_MARGIN, self.hearing,
                           _NONE_SILENT if silent is None else silent))
