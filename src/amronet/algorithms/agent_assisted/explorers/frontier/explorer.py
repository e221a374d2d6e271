"""The ``"frontier"`` explorer: per-agent state around the shared knowledge grid and the navigation kernel."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from amronet.algorithms.agent_assisted.explorers.base import EXPLORERS, Explorer
from amronet.algorithms.agent_assisted.explorers.frontier.distance import gap_to_uncovered
from amronet.algorithms.agent_assisted.explorers.frontier.knowledge import (
    KnowledgeGrid,
    clearance_offsets,
    paint_covered,
    paint_nodes,
)
from amronet.algorithms.agent_assisted.explorers.frontier.navigation import navigate
from amronet.algorithms.agent_assisted.explorers.frontier.planning import search_buffers, window_buffers
from amronet.algorithms.agent_assisted.explorers.frontier.state import (
    STUCK_RADIUS,
    AgentPlans,
    MapLayers,
    NavBuffers,
    NavSettings,
    StepInputs,
)
from amronet.algorithms.agent_assisted.explorers.random_walk import RandomExplorer
from amronet.engine.sensing import beam_angles

__all__ = ["FrontierExplorer", "FrontierTuning"]


def _least(gap: np.ndarray) -> float:
    """``max(0, gap.min())``: the least a target's gap adds to its score (``gap`` holds no NaN)."""
    return max(0.0, float(gap.min()))


@dataclass(frozen=True)
class FrontierTuning:
    """How the frontier explorer's strategy is tuned; the defaults are those of an explorer picked by name.

    Attributes:
        resolution: Cell size of the knowledge grid in metres.
        clearance: Cells within this distance (metres, centre to centre) of an occupied cell or a deployed node
            are not traversable; about the agent's body radius (a Pioneer's is 0.22 m). With 0.25 m cells,
            0.3 m keeps a 1 m doorway open.
        cover_margin: A node covers cells within ``(1 - cover_margin) r_c``; keep it below the deployment's
            ``loss_margin`` (0.05) so that an agent in an uncovered cell is about to lose its references.
        window: Targets have a seen uncovered cell or a frontier cell within this many cells.
        claim_radius: Targets within this many metres of another agent's goal are left to it while others
            exist; ``None``: ``r_c / 2``.
        gap_weight: Weight of a target's distance to uncovered space in its score.
        replan_every: Seconds between periodic replans.
        stuck_after: Seconds within :data:`STUCK_RADIUS` of one point after which the goal is given up.
        approach_time: Longest straight approach, in seconds, to an uncovered cell beside a reached target.
        lookahead: The agent aims at most this many path cells ahead.
        robot_radius: A reading ending within this many metres of a known robot marks no obstacle.
        lane: Half-width in metres of the lane ahead that must be clear of near readings.
    """

    resolution: float = 0.25
    clearance: float = 0.3
    cover_margin: float = 0.02
    window: int = 2
    claim_radius: float | None = None
    gap_weight: float = 1.5
    replan_every: float = 5.0
    stuck_after: float = 10.0
    approach_time: float = 4.0
    lookahead: int = 4
    robot_radius: float = 0.3
    lane: float = 0.25


@EXPLORERS.register("frontier")
class FrontierExplorer(Explorer):
    """Frontier exploration on a knowledge grid shared by the agents (see the package's docstring).

    The first five arguments are those of :class:`~amronet.algorithms.agent_assisted.explorers.base.Explorer`;
    ``tuning`` tunes the strategy (:class:`FrontierTuning`'s defaults when the explorer is picked by name). The explorer
    keeps per-agent state between calls: it must always be called with the same agents, in the same order.

    Args:
        turn_noise: Heading noise of the random fallback, radians per square-root second.
        avoid_range: Sonar readings nearer than this (metres) must keep out of the lane ahead.
        dt: Step length in seconds.
        r_c: Communication radius.
        extent: ``(xmin, xmax, ymin, ymax)`` of the area in metres.
        tuning: The strategy's settings (default: :class:`FrontierTuning`'s defaults).

    Attributes:
        grid: The shared :class:`KnowledgeGrid`.
        covered: Cells covered by the deployed nodes.
        robots: Cells next to deployed nodes.
        visited: Targets reached or given up.
        plans: What every agent plans (:class:`~amronet.algorithms.agent_assisted.explorers.frontier.state.AgentPlans`);
            ``plans.active``: the agent followed a path or an approach in the last call.
        steps: How many times :meth:`steer` was called.
    """

    def __init__(self, turn_noise: float, avoid_range: float, dt: float, r_c: float,
                 extent: tuple[float, float, float, float], *, tuning: FrontierTuning | None = None) -> None:
        super().__init__(turn_noise, avoid_range, dt, r_c, extent)
        t = FrontierTuning() if tuning is None else tuning
        resolution, clearance = t.resolution, t.clearance
        self.grid = KnowledgeGrid(extent, resolution)
        self.clearance = clearance
        self.cover_radius = (1.0 - t.cover_margin) * r_c
        self.claim_radius = 0.5 * r_c if t.claim_radius is None else t.claim_radius
        self.gap_weight = t.gap_weight
        self.robot_radius = t.robot_radius
        self.lane = t.lane
        self.window = int(t.window)
        self.lookahead = int(t.lookahead)
        self._steps_of = (max(1, round(t.replan_every / dt)), max(1, round(t.stuck_after / dt)),
                          max(1, round(t.approach_time / dt)))
        rows, cols = self.grid.shape
        self.covered = np.zeros((rows, cols), dtype=np.bool_)
        self.robots = np.zeros((rows, cols), dtype=np.bool_)
        self.gap = gap_to_uncovered(self.covered)
        self.visited = np.zeros((rows, cols), dtype=np.bool_)
        self._no_robots = np.zeros((rows, cols), dtype=np.bool_)
        self._off_r, self._off_c = clearance_offsets(clearance, resolution)
        marks, counts = window_buffers((rows, cols))
        # synced: -1, every view is computed again on the first plan (see NavBuffers)
        self._work = NavBuffers(search=search_buffers(rows * cols), trav=np.zeros((2, rows, cols), dtype=np.bool_),
                                marks=marks, counts=counts, synced=np.full(4, -1, dtype=np.int64),
                                cells_r=np.zeros(0, dtype=np.int64), cells_c=np.zeros(0, dtype=np.int64),
                                least_gap=np.array([_least(self.gap)]))
        self._nodes_key: bytes | None = None
        """The deployed nodes' coordinates as last painted, as bytes: a change of any of them repaints."""
        self._nodes = np.zeros((0, 2))
        self._settings_for: tuple[float, NavSettings, float] | None = None
        self.steps = 0
        self.plans = AgentPlans.start(0, rows * cols)
        self._fallback = RandomExplorer(turn_noise, avoid_range, dt, r_c, extent)

    def steer(self, heading: np.ndarray, who: np.ndarray, scans: np.ndarray, sensor_range: float,  # noqa: D102
              refused: np.ndarray, rng: np.random.Generator, xy: np.ndarray, deployed_xy: np.ndarray) -> None:
        who = np.asarray(who, dtype=np.int64)
        if len(who) == 0:
            return
        self.grid.integrate(xy[who], heading[who], scans, sensor_range, deployed_xy, self.robot_radius)
        self.plan_and_steer(heading, who, scans, sensor_range, refused, rng, xy, deployed_xy)

    def plan_and_steer(self, heading: np.ndarray, who: np.ndarray, scans: np.ndarray, sensor_range: float,
                       refused: np.ndarray, rng: np.random.Generator, xy: np.ndarray, deployed_xy: np.ndarray) -> None:
        """What :meth:`steer` does once the readings are in the grid: replan and set the agents' headings.

        For a caller that integrates the readings itself, in a compiled pass of its own
        (:mod:`amronet.algorithms.agent_assisted.fast`); the arguments are :meth:`steer`'s, ``who`` int64 and not empty.
        """
        m = len(who)
        if m != len(self.plans.goal):
            self.plans = AgentPlans.start(m, self.grid.shape[0] * self.grid.shape[1])
        grid = self.grid
        res = grid.resolution
        key = np.ascontiguousarray(deployed_xy, dtype=float).tobytes()  # exact, and cheaper than a sum
        refresh = key != self._nodes_key
        if refresh:
            self._nodes_key = key
            self._paint(np.ascontiguousarray(deployed_xy, dtype=float).reshape(-1, 2))
            self.gap = self.gap_weight * gap_to_uncovered(self.covered)
            self._work.least_gap[0] = _least(self.gap)
            self._work.synced[1:3] = -1  # the uncovered counts and the traversable cells must be computed again
        settings, avoid = self._settings(sensor_range)
        fresh = -np.pi + (2.0 * np.pi) * rng.random(m)  # rng.uniform(-pi, pi, m), the same numbers at less cost
        cells_r, cells_c = grid.buffers(max(sensor_range, (self.lookahead + 2) * res * 1.5))
        if cells_r is not self._work.cells_r:  # the grid's scratch cell lists grew
            self._work = self._work._replace(cells_r=cells_r, cells_c=cells_c)
        # built by position, in the order of the fields (keywords cost a dictionary per step)
        step = StepInputs(self.steps, refresh, xy, heading, who, np.minimum(scans, avoid), beam_angles(scans.shape[1]),
                          np.asarray(refused, dtype=np.bool_), fresh)
        layers = MapLayers(grid.score, grid.seen, grid.row_stamp, grid.stamp, self.robots, self._no_robots,
                           self.covered, self.gap, self.visited)
        navigate(step, layers, settings, self.plans, self._work)
        self.steps += 1
        if np.count_nonzero(self.plans.active) < m:  # (a tenth of ndarray.all's cost on a few agents)
            self.steer_idle(heading, who, scans, sensor_range, step.refused, rng, xy, deployed_xy)

    def navigation_inputs(self, sensor_range: float, m: int, deployed_xy: np.ndarray) -> tuple | None:
        """What :meth:`plan_and_steer` hands its navigation kernel that stays the same from step to step.

        For a compiled caller that plans and steers ``m`` agents for several steps in a row
        (:mod:`amronet.algorithms.agent_assisted.stretch_kernels`), each step as :meth:`plan_and_steer` would:
        ``(avoid, layers, settings,
        plans, buffers)`` (the last four as plain tuples; ``layers`` as in
        :class:`~amronet.algorithms.agent_assisted.explorers.frontier.state.MapLayers` from ``robots`` on), or ``None``
        when the next
        call would not be such a step: the deployed nodes are not those last painted, or the agents changed.
        """
        if m != len(self.plans.goal):
            return None
        if np.ascontiguousarray(deployed_xy, dtype=float).tobytes() != self._nodes_key:
            return None
        settings, avoid = self._settings(sensor_range)
        cells_r, cells_c = self.grid.buffers(max(sensor_range, (self.lookahead + 2) * self.grid.resolution * 1.5))
        if cells_r is not self._work.cells_r:
            self._work = self._work._replace(cells_r=cells_r, cells_c=cells_c)
        layers = (self.robots, self._no_robots, self.covered, self.gap, self.visited)
        return avoid, layers, tuple(settings), tuple(self.plans), tuple(self._work)

    def steer_idle(self, heading: np.ndarray, who: np.ndarray, scans: np.ndarray, sensor_range: float,
                   refused: np.ndarray, rng: np.random.Generator, xy: np.ndarray, deployed_xy: np.ndarray) -> None:
        """The end of :meth:`plan_and_steer`: the agents its plans left idle (``plans.active`` false) walk at random.

        The arguments are :meth:`plan_and_steer`'s (``refused`` of the agents ``who``, boolean).
        """
        idle = ~self.plans.active
        self._fallback.steer(heading, who[idle], scans[idle], sensor_range, refused[idle], rng, xy, deployed_xy)

    def _paint(self, nodes: np.ndarray) -> None:
        """Paint :attr:`covered` and :attr:`robots` for the deployed ``nodes`` ``(D, 2)``.

        When the nodes only grew (the last ones painted come first, unchanged) only the new ones are painted:
        painting is a union of disks, so the cells are the same.
        """
        grid = self.grid
        ox, oy = grid.origin
        res = grid.resolution
        old = self._nodes
        if len(nodes) >= len(old) and np.array_equal(nodes[:len(old)], old):
            new = nodes[len(old):]
            paint_nodes(self.covered, ox, oy, res, new, self.cover_radius)
            paint_nodes(self.robots, ox, oy, res, new, self.clearance)
        else:
            paint_covered(self.covered, ox, oy, res, nodes, self.cover_radius)
            paint_covered(self.robots, ox, oy, res, nodes, self.clearance)
        self._nodes = nodes.copy()

    def _settings(self, sensor_range: float) -> tuple[NavSettings, float]:
        """The navigation kernel's parameters and the avoidance reach, for this sensor range."""
        if self._settings_for is None or self._settings_for[0] != sensor_range:
            grid = self.grid
            res = grid.resolution
            avoid = min(sensor_range, self.avoid_range)
            replan, stuck, approach = self._steps_of
            settings = NavSettings(
                origin_x=float(grid.origin[0]), origin_y=float(grid.origin[1]), resolution=res, off_r=self._off_r,
                off_c=self._off_c, window=self.window, escape=math.ceil(self.clearance / res) + 1,
                replan_every=replan, stuck_after=stuck, lookahead=self.lookahead, approach_steps=approach,
                reach=float(avoid), stuck_radius=STUCK_RADIUS, claim_r2=float((self.claim_radius / res) ** 2),
                reach_tol=0.75 * res, lane=float(self.lane))
            self._settings_for = (sensor_range, settings, avoid)
        return self._settings_for[1], self._settings_for[2]
