"""The ``"frontier"`` explorer: per-agent state around the shared knowledge grid and the navigation kernel."""

from __future__ import annotations

import math

import numpy as np

from amronet.algorithms.explorers import Explorer, register_explorer
from amronet.algorithms.frontier.distance import gap_to_uncovered
from amronet.algorithms.frontier.knowledge import KnowledgeGrid, _offsets, _paint_covered, _paint_nodes
from amronet.algorithms.frontier.navigation import _navigate
from amronet.algorithms.frontier.planning import _search_buffers, _window_buffers
from amronet.algorithms.frontier.state import _APPR, _GOAL, _I_LOOK, _KIND, _LAST_PLAN, _N_STATE, _REASON, STUCK_RADIUS
from amronet.motion import random_walk
from amronet.sensing import beam_angles

__all__ = ["FrontierExplorer"]


def _state_column(col: int, doc: str) -> property:
    """A read-only property: column ``col`` of the per-agent state (a view, one entry per agent)."""

    def get(self: FrontierExplorer) -> np.ndarray:
        return self.state[:, col]

    return property(get, doc=doc)


@register_explorer("frontier")
class FrontierExplorer(Explorer):
    """Frontier exploration on a knowledge grid shared by the agents (see the package's docstring).

    The first five arguments are those of :class:`~amronet.algorithms.explorers.Explorer`; the others tune
    the strategy and keep their defaults when the explorer is picked by name. The explorer keeps per-agent
    state between calls: it must always be called with the same agents, in the same order.

    Args:
        turn_noise: Heading noise of the random fallback, radians per square-root second.
        avoid_range: Sonar readings nearer than this (metres) must keep out of the lane ahead.
        dt: Step length in seconds.
        r_c: Communication radius.
        extent: ``(xmin, xmax, ymin, ymax)`` of the area in metres.
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

    Attributes:
        grid: The shared :class:`KnowledgeGrid`.
        covered: Cells covered by the deployed nodes.
        robots: Cells next to deployed nodes.
        visited: Targets reached or given up.
        state: Per-agent state ``(A, 10)``: goal (flat cell, -1: none, the agent explores at random), its
            kind, path length, position on the path, step of the last plan, step it last moved away,
            why it last replanned (a code into :data:`REPLAN_REASONS`), planned through nodes, cell it
            approaches straight (-1: none), step the approach ends.
    """

    def __init__(self, turn_noise: float, avoid_range: float, dt: float, r_c: float,
                 extent: tuple[float, float, float, float], *, resolution: float = 0.25, clearance: float = 0.3,
                 cover_margin: float = 0.02, window: int = 2, claim_radius: float | None = None,
                 gap_weight: float = 1.5, replan_every: float = 5.0, stuck_after: float = 10.0,
                 approach_time: float = 4.0, lookahead: int = 4, robot_radius: float = 0.3,
                 lane: float = 0.25) -> None:
        super().__init__(turn_noise, avoid_range, dt, r_c, extent)
        self.grid = KnowledgeGrid(extent, resolution)
        self.clearance = clearance
        self.cover_radius = (1.0 - cover_margin) * r_c
        self.claim_radius = 0.5 * r_c if claim_radius is None else claim_radius
        self.gap_weight = gap_weight
        self.robot_radius = robot_radius
        self.lane = lane
        self.off_r, self.off_c = _offsets(clearance, resolution)
        self.settings = np.array([window, math.ceil(clearance / resolution) + 1, max(1, round(replan_every / dt)),
                                  max(1, round(stuck_after / dt)), lookahead, max(1, round(approach_time / dt))],
                                 dtype=np.int64)
        rows, cols = self.grid.shape
        self.covered = np.zeros((rows, cols), dtype=np.bool_)
        self.robots = np.zeros((rows, cols), dtype=np.bool_)
        self.gap = gap_to_uncovered(self.covered)
        self.visited = np.zeros((rows, cols), dtype=np.bool_)
        self._no_robots = np.zeros((rows, cols), dtype=np.bool_)
        self._trav = np.zeros((2, rows, cols), dtype=np.bool_)
        self._marks, self._counts = _window_buffers((rows, cols))
        self._synced = np.full(4, -1, dtype=np.int64)  # see _navigate
        self._search = _search_buffers(rows * cols)
        self._nodes_key: tuple[int, float] | None = None
        self._nodes = np.zeros((0, 2))
        self._reals_for: tuple[float, np.ndarray, float] | None = None
        self.steps = 0
        self._start(0)

    def _start(self, n_agents: int) -> None:
        rows, cols = self.grid.shape
        self.state = np.zeros((n_agents, _N_STATE), dtype=np.int64)
        self.state[:, [_GOAL, _LAST_PLAN, _APPR]] = -1
        self.anchor = np.full((n_agents, 2), np.inf)
        self.paths = np.zeros((n_agents, rows * cols), dtype=np.int64)
        self.active = np.zeros(n_agents, dtype=np.bool_)

    goal = _state_column(_GOAL, "Flat goal cell of every agent (-1: none, it explores at random).")
    kind = _state_column(_KIND, "Target kind of every agent's goal.")
    reason = _state_column(_REASON, "Why every agent last replanned (a code into :data:`REPLAN_REASONS`).")
    last_plan = _state_column(_LAST_PLAN, "Step of every agent's last plan.")

    def goals_xy(self) -> np.ndarray:
        """Current goal of every agent ``(A, 2)`` in metres (NaN where it explores at random)."""
        cols = self.grid.shape[1]
        goal = self.goal
        out = self.grid.centre(goal // cols, goal % cols)
        out[goal < 0] = np.nan
        return out

    def steer(self, heading: np.ndarray, who: np.ndarray, scans: np.ndarray, sensor_range: float,  # noqa: D102
              refused: np.ndarray, rng: np.random.Generator, xy: np.ndarray, deployed_xy: np.ndarray) -> None:
        who = np.asarray(who, dtype=np.int64)
        m = len(who)
        if m == 0:
            return
        if m != len(self.state):
            self._start(m)
        grid = self.grid
        res = grid.resolution
        grid.integrate(xy[who], heading[who], scans, sensor_range, deployed_xy, self.robot_radius)
        key = (len(deployed_xy), float(deployed_xy.sum()))
        refresh = key != self._nodes_key
        if refresh:
            self._nodes_key = key
            self._paint(np.ascontiguousarray(deployed_xy, dtype=float).reshape(-1, 2))
            self.gap = self.gap_weight * gap_to_uncovered(self.covered)
            self._synced[1:3] = -1  # the uncovered counts and the traversable cells must be computed again
        reals, avoid = self._reals(sensor_range)
        fresh = rng.uniform(-np.pi, np.pi, size=m)
        buf_r, buf_c = grid.buffers(max(sensor_range, (self.settings[_I_LOOK] + 2) * res * 1.5))
        _navigate(self.steps, refresh, xy, heading, who, np.minimum(scans, avoid), beam_angles(scans.shape[1]),
                  np.asarray(refused, dtype=np.bool_), fresh, grid.score, grid.seen, self.robots, self._no_robots,
                  self.covered, self.gap, self.visited, self.off_r, self.off_c, self.settings, reals, self.state,
                  self.anchor, self.paths, self._search, self._trav, self._marks, self._counts, grid.row_stamp,
                  grid.stamp, self._synced, buf_r, buf_c, self.active)
        self.steps += 1
        if not self.active.all():
            idle = ~self.active
            random_walk(heading, who[idle], np.minimum(scans[idle], avoid), avoid, np.asarray(refused)[idle], rng,
                        self.turn_noise * np.sqrt(self.dt))

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
            _paint_nodes(self.covered, ox, oy, res, new, self.cover_radius)
            _paint_nodes(self.robots, ox, oy, res, new, self.clearance)
        else:
            _paint_covered(self.covered, ox, oy, res, nodes, self.cover_radius)
            _paint_covered(self.robots, ox, oy, res, nodes, self.clearance)
        self._nodes = nodes.copy()

    def _reals(self, sensor_range: float) -> tuple[np.ndarray, float]:
        """The navigation kernel's real settings (``_F_*``) and the avoidance reach, for this sensor range."""
        if self._reals_for is None or self._reals_for[0] != sensor_range:
            res = self.grid.resolution
            avoid = min(sensor_range, self.avoid_range)
            reals = np.array([self.grid.origin[0], self.grid.origin[1], res, avoid, STUCK_RADIUS,
                              (self.claim_radius / res) ** 2, 0.75 * res, self.lane])
            self._reals_for = (sensor_range, reals, avoid)
        return self._reals_for[1], self._reals_for[2]
