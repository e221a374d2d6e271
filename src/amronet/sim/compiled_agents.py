"""The compiled step of agent-assisted runs: the agents' sense, tracking, grid update and move in two compiled calls.

An agent-assisted step of a few agents is mostly glue: the sense phase, the controller's ``decide``, the explorer's
``steer`` and the move phase each call a kernel or two between NumPy calls on small arrays. In most steps no agent
has to act (release a router, turn back): then :class:`CompiledAgents` does

1. one compiled call (:func:`~amronet.sim.step_kernels.sense_track_agents`): the agents' range rings, their reference
   tracking and, for the frontier explorer when no agent has to act, their readings in its knowledge grid;
2. the explorer's steering as it is (its own random draws and kernels; for the frontier explorer the part after
   the grid update, :meth:`~amronet.algorithms.explorers.frontier.FrontierExplorer.plan_and_steer`);
3. one compiled call (:func:`~amronet.sim.step_kernels.drive_movers`): the agents' moves with the collision
   checks, their distances and the refused moves.

In a step where an agent has to act, the controller's own Python takes over after the tracking
(:meth:`~amronet.algorithms.agent_assisted.AgentAssisted.decide_tracked`) and the move phase follows as the loop runs
it; while a router put down settles or a triangle router drives to its goal (other robots move), the whole step is
the loop's phases. Every computation is the one the phases do, in the same order, so the result is the same bit for
bit (``tests/test_compiled_step.py`` compares both paths).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING

import numpy as np

from amronet.algorithms.agent_assisted import AgentAssisted
from amronet.algorithms.base import Command, Readings, StepInput
from amronet.algorithms.explorers.frontier import FrontierExplorer, KnowledgeGrid
from amronet.engine.sensing import range_scan
from amronet.sim.agent_stretch import QuietStretch
from amronet.sim.phases import move, sense
from amronet.sim.step_kernels import drive_movers, sense_track_agents
from amronet.sim.surroundings import Surroundings

if TYPE_CHECKING:
    from amronet.sim.loop import Loop

__all__ = ["CompiledAgents"]


class CompiledAgents:
    """Sense, decide and move of an agent-assisted run (see the module docstring).

    Args:
        loop: The loop whose phases it does; :meth:`applies` must hold.
    """

    def __init__(self, loop: Loop) -> None:
        c = loop.controller
        assert isinstance(c, AgentAssisted)
        sw = loop.swarm
        self.loop, self.controller, self.explorer = loop, c, c.explorer
        self.frontier = type(c.explorer) is FrontierExplorer
        """Whether the readings go into the frontier explorer's grid in the compiled call."""
        self.knowledge = c.explorer.grid if self.frontier else KnowledgeGrid((0, 1, 0, 1), 1)
        """The grid the compiled call updates (a stand-in of the same types for other explorers: left alone)."""
        self.robot_radius = float(c.explorer.robot_radius) if self.frontier else 0.0
        self.around = Surroundings(loop, sw.models[c.agent_model])
        self.stretch = QuietStretch(self) if QuietStretch.applies(self) else None
        """Quiet steps in one compiled call (:mod:`amronet.sim.agent_stretch`), or ``None``."""

    @staticmethod
    def applies(loop: Loop) -> bool:
        """Whether the loop is one agent-assisted run whose agents act by the paper's rule.

        No faults, no batch, the paper's drop rule with its routers relaying at once and tethered agents, no
        repair, no reverse drops, no routers driving to goals: the steps where nothing but the agents move.
        """
        c = loop.controller
        return (isinstance(c, AgentAssisted) and loop.groups is None and not loop.scenario.faults
                and not c.general_path and c.relocator is None and c.strips is None and c.trails is None
                and c.needs_range_readings and len(c.agents) > 0)

    def step(self) -> None:
        """Sense, decide and move once: what the loop's three phases and the controller do, bit for bit."""
        c = self.controller
        if c.settle_at or c.moving_triangles:  # another robot moves or settles: the phases one by one
            self._phases()
            return
        n_before = len(self.loop.swarm)
        scans, n_cand, n_losing = self._sense_track()
        if n_cand or n_losing:  # an agent acts: the controller's own rules, then the move phase
            self.act(n_before, n_cand, n_losing, scans)
            return
        if self.frontier:  # the readings are in its grid already
            self.knowledge.stamp += 1
        self._steer(scans)
        self.drive()

    def _sense_track(self) -> tuple[np.ndarray, int, int]:
        """The agents' rings and reference tracking (and, in a quiet step, their readings in the frontier grid)."""
        loop, c, sw = self.loop, self.controller, self.loop.swarm
        table = loop.table
        is_ref, deployed_xy = c.deployed_nodes()
        grid, a = self.knowledge, self.around
        several = len(sw.xy) > 1
        s_csr = a.near(sw.xy, table, float(a.sensor_range + a.largest_radius()))
        buf_r, buf_c = grid.buffers(a.sensor_range)
        scans = np.empty((len(c.agents), len(a.angles)))  # fresh, as the sense phase's: an explorer may keep it
        n_cand, n_losing = sense_track_agents(
            *a.grid, sw.xy, sw.heading, sw.radius, c.agents, a.angles, a.sensor_range, *s_csr, several, scans,
            c.current, is_ref, sw.status, table.indptr, table.indices, table.dist, c.wants_other, c.left, c.r_eff,
            c.nearest_d, c.other_ref, self.frontier, grid.score, grid.seen, float(grid.origin[0]),
            float(grid.origin[1]), float(grid.resolution), deployed_xy, self.robot_radius, buf_r, buf_c,
            grid.row_stamp, grid.stamp + 1)
        return scans, n_cand, n_losing

    def act(self, n_before: int, n_cand: int, n_losing: int, scans: np.ndarray, readings: Readings | None = None
            ) -> None:
        """The rest of a step in which an agent acts: the controller's own rules, then the move phase.

        ``readings``: this step's readings when other robots than the agents sense (default: the agents' ``scans``).
        """
        c = self.controller
        self._decide_and_move(lambda step: c.decide_tracked(step, n_before, n_cand, n_losing),
                              readings or Readings({c.agent_model: (c.agents, scans)}))

    def finish(self, n_before: int, readings: Readings) -> None:
        """The rest of a step whose agents are steered: the other movers steer, then the move phase (all of them)."""
        c = self.controller
        self._decide_and_move(lambda step: c.movers_command(step, n_before), readings)

    def readings(self, scans: np.ndarray, others: np.ndarray) -> Readings:
        """This step's readings: the agents' ``scans`` and the rings of ``others`` (one model, not the agents').

        The rings of ``others`` as the sense phase casts them (:func:`~amronet.sim.phases.sense`).
        """
        c, loop = self.controller, self.loop
        groups = {c.agent_model: (c.agents, scans)}
        if len(others):
            sw = loop.swarm
            model = int(sw.model[others[0]])
            spec = sw.models[model]
            groups[model] = (others, range_scan(loop.world.omap, sw.xy, sw.heading, others, spec.sensor_beams,
                                                spec.sensor_range, radius=sw.radius, table=loop.table))
        return Readings(groups)

    def _steer(self, scans: np.ndarray) -> None:
        """The explorer's steering as it is (for the frontier explorer the part after the grid update)."""
        c, sw, a = self.controller, self.loop.swarm, self.around
        steer = self.explorer.plan_and_steer if self.frontier else self.explorer.steer
        steer(sw.heading, c.agents, scans, a.sensor_range, c.refused[c.agents], c.rng, sw.xy, c.deployed_nodes()[1])

    def moves(self) -> tuple[np.ndarray, float]:
        """The agents' move lengths this step and the reach of their collision checks, as the move phase has them."""
        length = self.explorer.speed(self.controller.agent_speed) * self.loop.dt
        # (ndarray.max costs more on a few agents)
        return length, 2.0 * self.around.largest_radius() + 2.0 * max(length.tolist())

    def drive(self) -> None:
        """The agents' moves (:func:`~amronet.sim.step_kernels.drive_movers`), as the move phase does them."""
        loop, c, sw, a = self.loop, self.controller, self.loop.swarm, self.around
        length, reach = self.moves()
        d_csr = a.near(sw.xy, loop.table, reach) if a.collisions else a.no_bodies(len(sw))
        drive_movers(*a.grid, c.agents, length, sw.xy, sw.heading, sw.radius, a.collisions, *d_csr, reach,
                     sw.distance, c.refused)

    def _phases(self) -> None:
        """The loop's sense, decide and move phases for this step (as :meth:`~amronet.sim.loop.Loop.step` runs them)."""
        loop = self.loop
        self._decide_and_move(self.controller.decide, sense(self.controller, loop.swarm, loop.world.omap, loop.table))

    def _decide_and_move(self, decide: Callable[[StepInput], Command], readings: Readings) -> None:
        """The controller's rules (``decide``, given this step's input) and the move phase, as the loop runs them."""
        loop, c, sw = self.loop, self.controller, self.loop.swarm
        before = sw.xy.copy()
        command = decide(StepInput(loop.steps, loop.t, loop.dt, loop.table, readings))
        # a router put down this step is not where the table has it: the move phase then searches the bodies afresh
        moved_table = loop.table if np.array_equal(before, sw.xy) else None
        move(c, command, sw, loop.world.omap, moved_table, loop.dt, self.around.collisions)
