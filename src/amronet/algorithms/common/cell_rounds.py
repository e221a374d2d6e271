"""The round structure the Voronoi-cell baselines share (VOR, Minimax, Lloyd): decide, then drive, round by round.

Wang, Cao and La Porta's protocols and Lloyd's algorithm go in rounds: every robot learns where its neighbours are,
builds its cell, picks its goal, and all move. Here a round lasts ``round_s`` seconds (by default the time a
router needs to drive the longest move, ``max_move_factor r_c``, at full speed). At the first step of a round
every router that has not failed builds its local cell (:func:`~amronet.algorithms.common.cells.local_cells`) from
the positions the nodes it hears announce, the obstacle points it remembers and the area's bounding box, and the
algorithm's rule (:meth:`CellRounds.goals`) says where it goes, or that it stays. A router with a move is in state
*explore* and drives straight to its goal at up to its maximum speed (the move is cut to ``max_move_factor r_c``);
one whose move the world refuses (a wall, a body) gives up the rest of that round's move. A router without a move
is in state *reference*: it stays, and decides again next round with the others. The run has converged when, at
the start of a round, no router has a move: nothing changes after that (:attr:`Controller.settled`).

Every step, each router that drives remembers the obstacle points its range sensors hit
(:class:`~amronet.algorithms.common.obstacle_memory.ObstacleMemory`). Everything is per robot and the rounds follow
the clock every run of a batch shares, so runs can be batched.
"""

from __future__ import annotations

import math
from abc import abstractmethod

import numpy as np

from amronet.algorithms.base import Command, Controller, Setup, StepInput
from amronet.algorithms.common.cell_params import CellParams, HoleParams
from amronet.algorithms.common.cells import local_cells
from amronet.algorithms.common.obstacle_memory import ObstacleMemory
from amronet.algorithms.common.polygons import Polygons
from amronet.engine.robots import Role, State
from amronet.engine.table import NeighbourTable

__all__ = ["CellRounds"]


def _enclosing_radius(extent: tuple[float, float, float, float], vertices: int) -> float:
    """A circumradius whose regular polygon about any point of ``extent`` holds the whole box (an unbounded cell)."""
    xmin, xmax, ymin, ymax = extent
    return 1.01 * float(np.hypot(xmax - xmin, ymax - ymin)) / math.cos(math.pi / vertices)


class CellRounds(Controller):
    """Base of the Voronoi-cell baselines: rounds, goals, driving, the obstacle memory (see the module docstring).

    A subclass says where each robot goes in :meth:`goals`.
    """

    params: CellParams
    batchable = True

    def __init__(self, params: CellParams, setup: Setup) -> None:
        super().__init__(params, setup)
        sw, p = self.swarm, self.params
        n = len(sw)
        self.routers = np.flatnonzero(sw.role == Role.ROUTER)
        self.reach = (p.cell_radius_factor * self.r_c if p.cell_radius_factor is not None
                      else _enclosing_radius(self.area.extent, p.disk_vertices))
        self.max_move = p.max_move_factor * self.r_c
        v_max = float(sw.max_speed[self.routers].max(initial=0.0))
        round_s = p.round_s if p.round_s is not None else (self.max_move / v_max if v_max > 0 else self.dt)
        self.round_steps = max(1, math.ceil(round_s / self.dt - 1e-9))
        self.goal = sw.xy.copy()
        self.last_move = np.zeros((n, 2))
        self.memory = ObstacleMemory(n, p.memory_points, p.memory_cell_m)
        self.generators = sw.role != Role.AGENT
        self.rounds = 0
        self.moves = np.zeros(n, dtype=np.int64)
        """Per robot, the rounds in which it had a move."""

    def unsettled(self) -> np.ndarray:  # noqa: D102
        return (self.swarm.state == State.EXPLORE) & (self.swarm.role == Role.ROUTER)

    def decide(self, step: StepInput) -> Command:  # noqa: D102
        sw = self.swarm
        driving = self.routers[sw.state[self.routers] == State.EXPLORE]
        if len(driving) and self.params.memory_points:
            model = int(sw.model[driving[0]])
            self.memory.remember(driving, step.readings.of(driving, model), sw.xy, sw.heading,
                                 sw.models[model].sensor_range, step.table, sw.radius)
        if step.index % self.round_steps == 0:
            self.new_round(step.table)
            driving = self.routers[sw.state[self.routers] == State.EXPLORE]
        ahead = self.goal[driving] - sw.xy[driving]
        left = np.hypot(ahead[:, 0], ahead[:, 1])
        go = left > 1e-9
        movers = driving[go]
        sw.heading[movers] = np.arctan2(ahead[go, 1], ahead[go, 0])
        speed = np.minimum(sw.max_speed[movers], left[go] / self.dt)
        return Command(movers, speed)

    def after_move(self, movers: np.ndarray, refused: np.ndarray) -> None:  # noqa: D102
        stuck = movers[refused]
        self.goal[stuck] = self.swarm.xy[stuck]

    def new_round(self, table: NeighbourTable) -> None:
        """Every router that has not failed builds its cell and takes its goal for the round."""
        sw = self.swarm
        who = self.routers[np.isin(sw.state[self.routers], (State.EXPLORE, State.REFERENCE))]
        self.rounds += 1
        if len(who) == 0:
            return
        cells = local_cells(who, sw.xy, self.generators, table, self.memory.remembered(),
                            self.area.extent, self.reach, self.params.disk_vertices)
        move, wants = self.goals(who, cells)
        length = np.hypot(move[:, 0], move[:, 1])
        move = move * np.minimum(1.0, self.max_move / np.maximum(length, 1e-300))[:, None]
        waits = np.zeros(len(who), dtype=bool)
        if self.oscillation_control:  # Wang et al.: never straight back; wait a round and see
            waits = wants & (np.einsum("ij,ij->i", move, self.last_move[who]) < 0.0)
            wants &= ~waits
        sw.state[who] = np.where(wants | waits, State.EXPLORE, State.REFERENCE)
        self.goal[who] = np.where(wants[:, None], sw.xy[who] + move, sw.xy[who])
        self.last_move[who] = np.where(wants[:, None], move, 0.0)
        self.moves[who[wants]] += 1

    oscillation_control: bool = False
    """Whether a robot whose move would point back against its last round's move waits a round instead."""

    @abstractmethod
    def goals(self, robots: np.ndarray, cells: Polygons) -> tuple[np.ndarray, np.ndarray]:
        """Where ``robots`` go this round: ``(move (M, 2), whether each moves (M,))``; cells are relative to them."""

    def report(self) -> dict[str, object]:
        """Rounds decided and moves made."""
        return self.report_run(slice(None))

    def report_run(self, robots: slice) -> dict[str, object]:  # noqa: D102
        return {"rounds": self.rounds, "moves": int(self.moves[robots].sum())}


class HoleRounds(CellRounds):
    """Rounds of Wang, Cao and La Porta's VOR and Minimax: a sensing disk of radius ``r_s`` and oscillation control.

    A subclass says where each robot goes in :meth:`goals`.
    """

    params: HoleParams

    def __init__(self, params: HoleParams, setup: Setup) -> None:
        super().__init__(params, setup)
        self.r_s = params.sensing_radius_factor * self.r_c
        """The sensing radius, metres."""

    @property
    def oscillation_control(self) -> bool:
        return self.params.oscillation_control
