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

from typing import TYPE_CHECKING

import numpy as np

from amronet.algorithms.agent_assisted import AgentAssisted
from amronet.algorithms.base import Readings, StepInput
from amronet.algorithms.explorers.frontier import FrontierExplorer, KnowledgeGrid
from amronet.engine.sensing import beam_angles, body_table
from amronet.sim.phases import move, sense
from amronet.sim.step_kernels import drive_movers, sense_track_agents
from amronet.world.space import clearance

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
        sw, omap = loop.swarm, loop.world.omap
        self.loop, self.controller, self.explorer = loop, c, c.explorer
        self.frontier = type(c.explorer) is FrontierExplorer
        """Whether the readings go into the frontier explorer's grid in the compiled call."""
        self.knowledge = c.explorer.grid if isinstance(c.explorer, FrontierExplorer) else KnowledgeGrid((0, 1, 0, 1), 1)
        """The grid the compiled call updates (a stand-in of the same types for other explorers: left alone)."""
        self.robot_radius = float(c.explorer.robot_radius) if self.frontier else 0.0
        model = sw.models[c.agent_model]
        self.grid = (omap.blocked.view(np.uint8), clearance(omap), float(omap.origin[0]), float(omap.origin[1]),
                     float(omap.resolution))
        self.angles = beam_angles(model.sensor_beams)
        self.sensor_range = float(model.sensor_range)
        self.collisions = loop.scenario.sim.robot_collisions
        self._biggest: tuple[np.ndarray, float] | None = None

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

    def _largest_radius(self) -> float:
        """The largest body radius (kept while the robots stay the same: robots are only ever added)."""
        radius = self.loop.swarm.radius
        if self._biggest is None or self._biggest[0] is not radius:
            self._biggest = (radius, float(radius.max()))
        return self._biggest[1]

    def step(self) -> None:
        """Sense, decide and move once: what the loop's three phases and the controller do, bit for bit."""
        loop, c, sw = self.loop, self.controller, self.loop.swarm
        table = loop.table
        if c.settle_at or c.moving_triangles:  # another robot moves or settles: the phases one by one
            self._phases()
            return
        agents = c.agents
        n_before = len(sw)
        is_ref, deployed_xy = c.deployed_nodes()
        explorer, grid = self.explorer, self.knowledge
        several = len(sw.xy) > 1
        s_csr = (body_table(sw.xy, float(self.sensor_range + self._largest_radius()), table) if several
                 else (np.zeros(len(sw) + 1, dtype=np.int64), np.zeros(0, dtype=np.int32), np.zeros(0)))
        buf_r, buf_c = grid.buffers(self.sensor_range)
        scans = np.empty((len(agents), len(self.angles)))  # fresh, as the sense phase's: an explorer may keep it
        n_cand, n_losing = sense_track_agents(
            *self.grid, sw.xy, sw.heading, sw.radius, agents, self.angles, self.sensor_range, *s_csr, several, scans,
            c.current, is_ref, sw.status, table.indptr, table.indices, table.dist, c.wants_other, c.left, c.r_eff,
            c.nearest_d, c.other_ref, self.frontier, grid.score, grid.seen, float(grid.origin[0]),
            float(grid.origin[1]), float(grid.resolution), deployed_xy, self.robot_radius, buf_r, buf_c,
            grid.row_stamp, grid.stamp + 1)
        if n_cand or n_losing:  # an agent acts: the controller's own rules, then the move phase
            readings = Readings({c.agent_model: (agents, scans)})
            before = sw.xy.copy()
            command = c.decide_tracked(StepInput(loop.steps, loop.t, loop.dt, table, readings), n_before, n_cand,
                                       n_losing)
            moved_table = table if np.array_equal(before, sw.xy) else None
            move(c, command, sw, loop.world.omap, moved_table, loop.dt, self.collisions)
            return
        if self.frontier:
            grid.stamp += 1
            explorer.plan_and_steer(sw.heading, agents, scans, self.sensor_range, c.refused[agents], c.rng, sw.xy,
                                    deployed_xy)
        else:
            explorer.steer(sw.heading, agents, scans, self.sensor_range, c.refused[agents], c.rng, sw.xy,
                           deployed_xy)
        length = explorer.speed(c.agent_speed) * loop.dt
        reach = 2.0 * self._largest_radius() + 2.0 * float(length.max())
        if self.collisions and several:
            d_csr = body_table(sw.xy, reach, table)
        else:
            d_csr = (np.zeros(len(sw) + 1, dtype=np.int64), np.zeros(0, dtype=np.int32), np.zeros(0))
        drive_movers(*self.grid, agents, length, sw.xy, sw.heading, sw.radius, self.collisions, *d_csr, reach,
                     sw.distance, c.refused)

    def _phases(self) -> None:
        """The loop's sense, decide and move phases for this step (as :meth:`~amronet.sim.loop.Loop.step` runs them)."""
        loop, c, sw = self.loop, self.controller, self.loop.swarm
        omap = loop.world.omap
        readings = sense(c, sw, omap, loop.table)
        before = sw.xy.copy()
        command = c.decide(StepInput(loop.steps, loop.t, loop.dt, loop.table, readings))
        moved_table = loop.table if np.array_equal(before, sw.xy) else None
        move(c, command, sw, omap, moved_table, loop.dt, self.collisions)
