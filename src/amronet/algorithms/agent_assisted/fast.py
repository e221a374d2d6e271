"""The compiled step of agent-assisted runs: the agents' sense, tracking, grid update and move in two compiled calls.

An agent-assisted step of a few agents is mostly glue: the sense phase, the controller's ``decide``, the explorer's
``steer`` and the move phase each call a kernel or two between NumPy calls on small arrays. In most steps no agent
has to act (release a router, turn back): then :class:`CompiledAgents` does

1. one compiled call (:func:`~amronet.algorithms.agent_assisted.kernels.sense_track_agents`): the agents' range rings,
their reference
   tracking and, for the frontier explorer when no agent has to act, their readings in its knowledge grid;
2. the explorer's steering as it is (its own random draws and kernels; for the frontier explorer the part after
   the grid update, :meth:`~amronet.algorithms.agent_assisted.explorers.frontier.FrontierExplorer.plan_and_steer`);
3. one compiled call (:func:`~amronet.algorithms.agent_assisted.kernels.drive_movers`): the agents' moves with the
collision
   checks, their distances and the refused moves.

Under a drop rule other than the paper's alone (or with ``when_empty: continue``, ``drop_settle_s``,
``reverse_drop``), whether an agent acts is the rule's: after the tracking, one more compiled call asks it
(:class:`~amronet.algorithms.agent_assisted.rule_check.RuleCheck`) and, in a quiet step, keeps its books. In a step
where an agent has to act, the controller's own Python takes over after the tracking
(:meth:`~amronet.algorithms.agent_assisted.controller.AgentAssisted.decide_tracked`) and the move phase follows as the
loop runs it. Triangle and strip routers on their way are sensed with the agents (their rings as the sense phase
casts them) and steered by the controller's Python (:meth:`CompiledAgents.finish`); only where such routers are of
the agents' own model is the whole step the loop's phases. Under ``repair: relocate`` or ``retrace`` the repair's
part of a quiet step is :class:`~.repair_step.RepairStep`'s, and the steps in which routers relocate or agents back
up are the loop's phases. Every computation is the one the phases do, in the same
order, so the result is the same bit for bit (``tests/test_compiled_step.py`` and
``tests/test_compiled_drop_rules.py`` compare both paths).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any, Protocol

import numpy as np

from amronet.algorithms.agent_assisted.explorers.frontier import FrontierExplorer, KnowledgeGrid
from amronet.algorithms.agent_assisted.kernels import (
    Knowledge,
    Ring,
    Robots,
    Tracking,
    drive_movers,
    integrate_agents,
    sense_track_agents,
)
from amronet.algorithms.agent_assisted.repair_step import RepairStep
from amronet.algorithms.agent_assisted.rule_check import RuleCheck
from amronet.algorithms.agent_assisted.stretch_kernels import TRIANGLE_RULES, TRIANGLES_ACT, triangle_goes
from amronet.algorithms.base import Command, Readings, StepInput
from amronet.algorithms.phases import move, sense
from amronet.algorithms.stepping import FastStep, StepContext, Stretched, Surroundings, Watch
from amronet.engine.robots import State
from amronet.engine.sensing import range_scan

__all__ = ["AgentControls", "CompiledAgents"]

_NO_ROBOTS = np.zeros(0, dtype=np.int64)
_OTHER_MOVERS = (State.TRIANGLE, State.STRIP)
"""The states of the released routers that move (relocating routers: :meth:`.repair_step.RepairStep.busy`)."""


class AgentControls(Protocol):
    """What the fast step reads and keeps of its controller: nothing else of it.

    The controller is :class:`~amronet.algorithms.agent_assisted.controller.AgentAssisted`: its names below are
    the declared interface between the two.
    """

    params: Any
    rng: Any
    dt: float
    r_c: float
    r_eff: float
    agents: np.ndarray
    agent_model: int
    agent_speed: float
    explorer: Any
    needs_range_readings: bool
    general_path: bool
    relocator: Any
    strips: Any
    trails: Any
    contact_since: np.ndarray
    links_by_distance: bool
    settle_at: Any
    swarm: Any
    bases: np.ndarray
    drop_rule: Any
    tether: bool
    reverse_after_s: float | None
    pending_until: np.ndarray
    reversing: np.ndarray
    moving_triangles: Any
    steering: Any
    current: np.ndarray
    wants_other: bool
    left: np.ndarray
    nearest_d: np.ndarray
    other_ref: np.ndarray
    refused: np.ndarray
    disabled: np.ndarray
    decide: Callable[[StepInput], Command]
    decide_tracked: Callable[..., Command]
    movers_command: Callable[..., Command]
    deployed_nodes: Callable[[], tuple[np.ndarray, np.ndarray]]
    served_pairs: Callable[[], Any]
    triangles_released: list
    _settle_dropped: Callable[[float], None]
    _back_up_at: Callable[[float, np.ndarray], None]


class CompiledAgents(FastStep):
    """Sense, decide and move of an agent-assisted run (see the module docstring).

    Args:
        controller: The loop's controller.
        context: The loop's step context; :meth:`applies` must hold.
    """

    def __init__(self, controller: AgentControls, context: StepContext) -> None:
        c = controller
        sw = context.swarm
        self.swarm, self.omap, self.controller, self.explorer = sw, context.omap, c, c.explorer
        self.frontier = type(c.explorer) is FrontierExplorer
        """Whether the readings go into the frontier explorer's grid in the compiled call."""
        self.knowledge = c.explorer.grid if self.frontier else KnowledgeGrid((0, 1, 0, 1), 1)
        """The grid the compiled call updates (a stand-in of the same types for other explorers: left alone)."""
        self.robot_radius = float(c.explorer.robot_radius) if self.frontier else 0.0
        self.around = a = Surroundings(context, sw.models[c.agent_model])
        self.grid = tuple(a.grid)
        """The map's grid as the kernels take it (a plain tuple: see :mod:`.kernels`)."""
        self.ring = tuple(Ring(a.angles, a.sensor_range))
        """The agents' ring as the kernels take it."""
        self._robots = Robots(sw.xy, sw.heading, sw.radius, sw.status, sw.distance)
        self._robots_plain = tuple(self._robots)
        self._tracking: Tracking | None = None
        self._tracking_plain: tuple = ()
        self._knowledge: Knowledge | None = None
        self._knowledge_plain: tuple = ()
        self.rules = RuleCheck(c) if c.general_path else None
        """The drop rule's compiled check (:class:`~.rule_check.RuleCheck`), or ``None`` under the paper's rule alone
        (an agent acts when it is about to lose its last reference)."""
        self.triangle_rule = TRIANGLE_RULES.get(c.params.triangular, TRIANGLES_ACT)
        self._served: tuple[int, np.ndarray] = (0, c.served_pairs())
        """The triangles served so far, as the compiled check reads them, and how many were."""
        self.repair = RepairStep(c, context) if c.relocator is not None else None
        """The repair's part of the step (``repair: relocate`` or ``retrace``), or ``None``."""
        self.quiet: Any = None
        """Quiet steps in one compiled call (:class:`.stretch.QuietStretch`, set by the controller where it applies),
        or ``None``."""

    @staticmethod
    def applies(controller: AgentControls, context: StepContext) -> bool:
        """Whether the loop is one agent-assisted run whose agents act by a drop rule the compiled check knows.

        One run (no batch), agents that read range rings, and the paper's drop rule or one
        :class:`~.rule_check.RuleCheck` knows; faults, ``agents.when_empty``, ``drop_settle_s``, ``reverse_drop``
        and the repairs (:class:`~.repair_step.RepairStep`) are all taken in. The steps where other robots than the
        agents move, routers relocating or agents backing up, go phase by phase.
        """
        c = controller
        return (context.groups is None and c.needs_range_readings and len(c.agents) > 0
                and (not c.general_path or RuleCheck.knows(c)))

    def step(self, now: StepInput) -> None:
        """Sense, decide and move once: what the loop's three phases and the controller do, bit for bit."""
        c = self.controller
        others = self.other_movers()
        if others is None or (self.repair is not None and self.repair.busy()):
            # other robots move that the compiled step does not sense (or relocate), agents back up: the phases
            self._phases(now)
            return
        if c.settle_at:  # (what decide does first, once the movers are known: the rings do not read states)
            c._settle_dropped(now.t)
        n_before = len(self.swarm)
        rules = self.rules
        scans, n_cand, n_losing = self._sense_track(now, rules is None)
        readings = self.readings(now, scans, others) if len(others) else None
        if ((n_cand and self.triangle_goes()) or (n_losing if rules is None else not rules.quiet(now, scans))):
            self.act(now, n_before, n_cand, n_losing, scans, readings)  # an agent acts: the controller's own rules
            return
        if self.frontier:
            if rules is not None or n_cand:  # the readings into its grid, as the sense pass puts them in a quiet step
                integrate_agents(self.robots(), c.agents, self.ring, scans, self._knowledge_plain,
                                 self.knowledge.stamp + 1)
            self.knowledge.stamp += 1
        self._steer(scans)
        if c.trails is not None:  # the reverse drop's books and the agents that back up (the contact the check read)
            assert rules is not None and rules.contact
            c._back_up_at(now.t, rules.last_contact)
        if readings is None:
            self.drive(now, None if self.repair is None else self.repair.quiet(now, scans))
        else:  # the triangle and strip routers steer in the controller's Python, then everybody moves
            self.finish(now, n_before, readings)

    def triangle_goes(self) -> bool:
        """Whether a triangle router goes out this step (:func:`~.stretch_kernels.triangle_goes`).

        Under the global rule the controller decides (always ``True``); otherwise agents that hear another network's
        reference and release none only look.
        """
        c = self.controller
        if self.triangle_rule == TRIANGLES_ACT:
            return True
        if len(c.triangles_released) != self._served[0]:
            self._served = (len(c.triangles_released), c.served_pairs())
        return bool(triangle_goes((self.triangle_rule, float(c.r_c), c.disabled, self._served[1]), c.agents,
                                  c.current, c.other_ref, c.left, self.swarm.xy))

    def other_movers(self) -> np.ndarray | None:
        """The robots other than the agents that the sense phase would sense this step (triangle and strip routers).

        ``None`` where the compiled step cannot sense them as it does: several models, or the agents'.
        """
        c, sw = self.controller, self.swarm
        if not c.moving_triangles and (c.strips is None or not c.strips.moving):
            return _NO_ROBOTS
        others = np.flatnonzero(sw.in_states(_OTHER_MOVERS))
        if len(others) == 0:
            return others
        model = sw.model[others]
        return None if model[0] == c.agent_model or (model != model[0]).any() else others

    @property
    def stretches(self) -> bool:  # noqa: D102
        return self.quiet is not None

    @property
    def silences(self) -> bool:  # noqa: D102
        return self.quiet is not None  # (its kernel drops the failed nodes' links from the tables it builds)

    @property
    def restores(self) -> bool:  # noqa: D102
        return self.quiet is not None  # (QuietStretch.take: Watch.restoring)

    def stretch(self, limit: int, now: StepInput, watch: Watch) -> Stretched | None:
        """Up to ``limit`` quiet steps in one call (:class:`.stretch.QuietStretch`), the failed nodes silent."""
        if self.quiet is None or watch.agents is None:
            return None
        return self.quiet.take(limit, now, watch.agents, watch.silent, watch.restoring)

    def robots(self) -> tuple:
        """The robots' arrays as the kernels take them (:class:`.kernels.Robots`, a plain tuple).

        Built again when the swarm's arrays are replaced (routers released).
        """
        sw, kept = self.swarm, self._robots
        if (kept.xy is not sw.xy or kept.heading is not sw.heading or kept.radius is not sw.radius
                or kept.status is not sw.status or kept.distance is not sw.distance):
            self._robots = Robots(sw.xy, sw.heading, sw.radius, sw.status, sw.distance)
            self._robots_plain = tuple(self._robots)
        return self._robots_plain

    def tracking(self, is_ref: np.ndarray) -> tuple:
        """The controller's reference tracking as the kernels take it (:class:`.kernels.Tracking`, a plain tuple).

        Built again when the controller's arrays are replaced (robots added) or the deployed nodes change.
        """
        c, kept = self.controller, self._tracking
        if (kept is None or kept.is_ref is not is_ref or kept.current is not c.current or kept.left is not c.left
                or kept.refused is not c.refused):
            self._tracking = Tracking(c.current, is_ref, c.wants_other, c.left, c.r_eff, c.nearest_d, c.other_ref,
                                      c.refused)
            self._tracking_plain = tuple(self._tracking)
        return self._tracking_plain

    def knowledge_for(self, nodes: np.ndarray, sensor_range: float) -> tuple:
        """The frontier grid and what its update reads as the kernels take them (:class:`.kernels.Knowledge`).

        ``nodes``: the deployed nodes' positions. Built again when they or the grid's scratch cell lists change.
        """
        grid, kept = self.knowledge, self._knowledge
        buf_r, buf_c = grid.buffers(sensor_range)
        if kept is None or kept.nodes is not nodes or kept.buf_r is not buf_r:
            self._knowledge = Knowledge(grid.cells, nodes, self.robot_radius, buf_r, buf_c)
            self._knowledge_plain = tuple(self._knowledge)
        return self._knowledge_plain

    def _sense_track(self, now: StepInput, integrate: bool = True) -> tuple[np.ndarray, int, int]:
        """The agents' rings and reference tracking (``integrate``: in a quiet step, readings in the grid)."""
        c, sw, a = self.controller, self.swarm, self.around
        table = now.table
        is_ref, deployed_xy = c.deployed_nodes()
        near = a.near(sw.xy, table, float(a.sensor_range + a.largest_radius()))
        scans = np.empty((len(c.agents), len(a.angles)))  # fresh, as the sense phase's: an explorer may keep it
        n_cand, n_losing = sense_track_agents(
            self.grid, self.robots(), c.agents, self.ring, near, scans, self.tracking(is_ref),
            (table.indptr, table.indices, table.dist), self.frontier and integrate,
            self.knowledge_for(deployed_xy, a.sensor_range),
            self.knowledge.stamp + 1)
        return scans, n_cand, n_losing

    def act(self, now: StepInput, n_before: int, n_cand: int, n_losing: int, scans: np.ndarray,
            readings: Readings | None = None) -> None:
        """The rest of a step in which an agent acts: the controller's own rules, then the move phase.

        ``readings``: this step's readings when other robots than the agents sense (default: the agents' ``scans``).
        """
        c = self.controller
        self._decide_and_move(now, lambda step: c.decide_tracked(step, n_before, n_cand, n_losing),
                              readings or Readings({c.agent_model: (c.agents, scans)}))

    def finish(self, now: StepInput, n_before: int, readings: Readings) -> None:
        """The rest of a step whose agents are steered: the other movers steer, then the move phase (all of them)."""
        c = self.controller
        self._decide_and_move(now, lambda step: c.movers_command(step, n_before), readings)

    def readings(self, now: StepInput, scans: np.ndarray, others: np.ndarray) -> Readings:
        """This step's readings: the agents' ``scans`` and the rings of ``others`` (one model, not the agents').

        The rings of ``others`` as the sense phase casts them (:func:`~amronet.algorithms.phases.sense`).
        """
        c = self.controller
        groups = {c.agent_model: (c.agents, scans)}
        if len(others):
            sw = self.swarm
            model = int(sw.model[others[0]])
            spec = sw.models[model]
            groups[model] = (others, range_scan(self.omap, sw.xy, sw.heading, others, spec.sensor_beams,
                                                spec.sensor_range, radius=sw.radius, table=now.table))
        return Readings(groups)

    def _steer(self, scans: np.ndarray) -> None:
        """The explorer's steering as it is (for the frontier explorer the part after the grid update)."""
        c, sw, a = self.controller, self.swarm, self.around
        steer = self.explorer.plan_and_steer if self.frontier else self.explorer.steer
        steer(sw.heading, c.agents, scans, a.sensor_range, c.refused[c.agents], c.rng, sw.xy, c.deployed_nodes()[1])

    def moves(self) -> tuple[np.ndarray, float]:
        """The agents' move lengths this step and the reach of their collision checks, as the move phase has them."""
        length = self.explorer.speed(self.controller.agent_speed) * self.controller.dt
        # (ndarray.max costs more on a few agents)
        return length, 2.0 * self.around.largest_radius() + 2.0 * max(length.tolist())

    def drive(self, now: StepInput, speed: np.ndarray | None = None) -> None:
        """The agents' moves (:func:`~.kernels.drive_movers`), as the move phase does them.

        ``speed``: their speeds, where the repair set them (default: the explorer's, :meth:`moves`).
        """
        c, sw, a = self.controller, self.swarm, self.around
        if speed is None:
            length, reach = self.moves()
        else:
            length = speed * c.dt
            reach = 2.0 * a.largest_radius() + 2.0 * max(length.tolist())
        near = a.near(sw.xy, now.table, reach) if a.collisions else a.no_bodies(len(sw))
        drive_movers(self.grid, self.robots(), c.agents, length, a.collisions, near, reach, c.refused)

    def _phases(self, now: StepInput) -> None:
        """The loop's sense, decide and move phases for this step (as :meth:`~amronet.sim.loop.Loop.step` runs them)."""
        self._decide_and_move(now, self.controller.decide, sense(self.controller, self.swarm, self.omap, now.table))

    def _decide_and_move(self, now: StepInput, decide: Callable[[StepInput], Command], readings: Readings) -> None:
        """The controller's rules (``decide``, given this step's input) and the move phase, as the loop runs them."""
        c, sw = self.controller, self.swarm
        before = sw.xy.copy()
        command = decide(StepInput(now.index, now.t, now.dt, now.table, readings))  # (dataclasses.replace, cheaper)
        # a router put down this step is not where the table has it: the move phase then searches the bodies afresh
        moved_table = now.table if np.array_equal(before, sw.xy) else None
        move(c, command, sw, self.omap, moved_table, now.dt, self.around.collisions)
