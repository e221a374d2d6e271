"""The frontier explorer's per-agent plans and the named inputs of its navigation kernel.

The agents' navigation (:func:`~amronet.algorithms.agent_assisted.explorers.frontier.navigation.navigate`) takes its
inputs as
five named tuples of arrays and numbers:

* :class:`AgentPlans`: what every agent plans, kept between steps and updated in place by the kernel;
* :class:`StepInputs`: this step's poses, readings and fresh random headings, and the headings to set;
* :class:`MapLayers`: the shared knowledge grid and the layers the explorer derives from it;
* :class:`NavSettings`: the strategy's parameters in grid units and steps;
* :class:`NavBuffers`: scratch space and derived views the kernel keeps up to date between steps.

Its compiled kernel gets them as plain tuples (numba types those fast) and unpacks each into local variables
named after its fields, in the order of the fields: a field added, removed or moved here must be so there too
(a test compares the two).
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

__all__ = [
    "APPROACHED",
    "BLOCKED",
    "NODE_DEPLOYED",
    "NOT_TARGET",
    "NO_GOAL",
    "PERIODIC",
    "REACHED",
    "REPLAN_REASONS",
    "STUCK",
    "STUCK_RADIUS",
    "AgentPlans",
    "MapLayers",
    "NavBuffers",
    "NavSettings",
    "StepInputs",
]

STUCK_RADIUS = 0.5
"""An agent that stayed within this many metres of one point for ``stuck_after`` seconds is stuck."""

NO_GOAL = 1
"""Replan reason: the agent had no goal and it was time to try again."""
REACHED = 2
"""Replan reason: the agent reached its goal."""
NOT_TARGET = 3
"""Replan reason: the goal stopped being a target."""
NODE_DEPLOYED = 4
"""Replan reason: a node was deployed (the targets' scores changed)."""
STUCK = 5
"""Replan reason: the agent stayed within :data:`STUCK_RADIUS` of one point too long (the goal is given up)."""
PERIODIC = 6
"""Replan reason: ``replan_every`` seconds passed since the last plan."""
BLOCKED = 7
"""Replan reason: a cell of the rest of the path stopped being traversable."""
APPROACHED = 8
"""Replan reason: the straight approach to an uncovered cell ended."""
REPLAN_REASONS = ("", "no goal", "reached", "not a target", "node deployed", "stuck", "periodic", "blocked",
                  "approached")
"""Names of the codes in :attr:`AgentPlans.reason` (0: never planned)."""


class AgentPlans(NamedTuple):
    """What every agent plans: one entry per agent, in the order the explorer is given them.

    The explorer keeps these between steps; the navigation kernel reads and updates them in place. Cells are
    flat indices ``row * cols + col`` into the knowledge grid; times are step numbers.

    Attributes:
        goal: Goal cell ``(A,)`` int64; -1: none (the agent explores at random).
        kind: Target kind of the goal ``(A,)`` int64
            (:data:`~amronet.algorithms.agent_assisted.explorers.frontier.planning.UNCOVERED` or ``FRONTIER``).
        path: Cells of the path to the goal ``(A, cells)`` int64; the first ``path_len`` are the path.
        path_len: Length of the path ``(A,)`` int64.
        path_pos: Index into ``path`` of the path cell the agent is nearest to ``(A,)`` int64.
        through_nodes: The path was planned through the deployed nodes ``(A,)`` bool.
        last_plan: Step of the last plan ``(A,)`` int64; -1: never planned.
        reason: Why the agent last replanned ``(A,)`` int64, a code into :data:`REPLAN_REASONS`.
        anchor: Where the agent last moved more than :data:`STUCK_RADIUS` from ``(A, 2)`` metres.
        last_move: Step at which it did ``(A,)`` int64.
        approach: Uncovered cell the agent drives straight at ``(A,)`` int64; -1: none.
        approach_until: Step at which that approach ends ``(A,)`` int64.
        active: Set by the kernel: the agent was steered (it has a path or an approach) ``(A,)`` bool; the
            others explore at random.
    """

    goal: np.ndarray
    kind: np.ndarray
    path: np.ndarray
    path_len: np.ndarray
    path_pos: np.ndarray
    through_nodes: np.ndarray
    last_plan: np.ndarray
    reason: np.ndarray
    anchor: np.ndarray
    last_move: np.ndarray
    approach: np.ndarray
    approach_until: np.ndarray
    active: np.ndarray

    @classmethod
    def start(cls, n_agents: int, n_cells: int) -> AgentPlans:
        """Plans of ``n_agents`` agents that have not planned yet, on a grid of ``n_cells`` cells."""

        def ints(fill: int) -> np.ndarray:
            return np.full(n_agents, fill, dtype=np.int64)

        return cls(goal=ints(-1), kind=ints(0), path=np.zeros((n_agents, n_cells), dtype=np.int64),
                   path_len=ints(0), path_pos=ints(0), through_nodes=np.zeros(n_agents, dtype=np.bool_),
                   last_plan=ints(-1), reason=ints(0), anchor=np.full((n_agents, 2), np.inf), last_move=ints(0),
                   approach=ints(-1), approach_until=ints(0), active=np.zeros(n_agents, dtype=np.bool_))


class StepInputs(NamedTuple):
    """One step's inputs of the navigation kernel.

    Attributes:
        now: The step number.
        nodes_changed: The deployed nodes changed since the last step (every agent with a goal replans).
        xy: Positions of all robots ``(N, 2)``.
        heading: Headings of all robots ``(N,)``; the kernel sets those of the agents it steers.
        who: The agents, indices into ``xy`` ``(A,)`` int64.
        scans: Their sonar readings ``(A, n_beams)``, clipped at the avoidance reach.
        angles: The beams' angles from the heading ``(n_beams,)``.
        refused: Which agents had their last move refused ``(A,)`` bool.
        fresh: A uniform random heading per agent ``(A,)``, taken after a refused move.
    """

    now: int
    nodes_changed: bool
    xy: np.ndarray
    heading: np.ndarray
    who: np.ndarray
    scans: np.ndarray
    angles: np.ndarray
    refused: np.ndarray
    fresh: np.ndarray


class MapLayers(NamedTuple):
    """The knowledge grid the agents share and the layers the explorer keeps over it, all ``(rows, cols)``.

    Attributes:
        score: Evidence counts
        (:attr:`~amronet.algorithms.agent_assisted.explorers.frontier.knowledge.KnowledgeGrid.score`).
        seen: Seen cells.
        row_stamp: Per row, the grid's stamp when a cell of the row last changed ``(rows,)``.
        stamp: The grid's stamp now.
        robots: Cells next to deployed nodes (not traversable).
        no_robots: All ``False``: what ``robots`` is for an agent that plans through the nodes.
        covered: Cells covered by the deployed nodes.
        gap: ``gap_weight`` times each cell's distance to uncovered space, in cells.
        visited: Targets reached or given up (updated by the kernel).
    """

    score: np.ndarray
    seen: np.ndarray
    row_stamp: np.ndarray
    stamp: int
    robots: np.ndarray
    no_robots: np.ndarray
    covered: np.ndarray
    gap: np.ndarray
    visited: np.ndarray


class NavSettings(NamedTuple):
    """The frontier explorer's parameters as the navigation kernel uses them (grid units and steps).

    Attributes:
        origin_x: World x of the grid's lower-left corner.
        origin_y: World y of the grid's lower-left corner.
        resolution: Cell size in metres.
        off_r: Row offsets of the cells within the clearance
            (:func:`~amronet.algorithms.agent_assisted.explorers.frontier.knowledge.clearance_offsets`).
        off_c: Their column offsets.
        window: Targets have a seen uncovered cell or a frontier cell within this many cells.
        escape: Near its own cell (this many cells, Chebyshev) an agent may cross free cells that are not
            traversable.
        replan_every: Steps between periodic replans.
        stuck_after: Steps within :attr:`stuck_radius` of one point after which the goal is given up.
        lookahead: The agent aims at most this many path cells ahead.
        approach_steps: Longest straight approach to an uncovered cell, in steps.
        reach: Sonar readings nearer than this (metres) must keep out of the lane ahead.
        stuck_radius: :data:`STUCK_RADIUS`.
        claim_r2: Squared radius, in cells, around another agent's goal within which targets are left to it.
        reach_tol: A goal is reached within this many metres of its cell's centre.
        lane: Half-width in metres of the lane ahead that must be clear of near readings.
    """

    origin_x: float
    origin_y: float
    resolution: float
    off_r: np.ndarray
    off_c: np.ndarray
    window: int
    escape: int
    replan_every: int
    stuck_after: int
    lookahead: int
    approach_steps: int
    reach: float
    stuck_radius: float
    claim_r2: float
    reach_tol: float
    lane: float


class NavBuffers(NamedTuple):
    """Scratch space of the navigation kernel, and the views of the grid it keeps up to date between steps.

    Attributes:
        search: Scratch parent, depth and queue of the search
            (:func:`~amronet.algorithms.agent_assisted.explorers.frontier.planning.search_buffers`).
        trav: Traversable cells ``(2, rows, cols)``: around the deployed nodes, and through them.
        marks: Frontier and seen uncovered cells ``(2, rows, cols)``
            (:func:`~amronet.algorithms.agent_assisted.explorers.frontier.planning.update_window_counts`).
        counts: Their window counts ``(2, rows, cols + 1)``.
        synced: The grid stamp each view reflects ``(4,)``: frontier counts, uncovered counts, ``trav[0]``,
            ``trav[1]``; -1 when it must be computed again (the explorer's business when ``covered`` or
            ``robots`` change).
        cells_r: Scratch rows of the cells a segment crosses.
        cells_c: Scratch columns of those cells.
        least_gap: ``max(0, gap.min())`` of the layers' ``gap`` ``(1,)``, the floor of the searches' scores
            (:class:`~amronet.algorithms.agent_assisted.explorers.frontier.planning.Targets`; the explorer's
            business when ``gap`` changes).
    """

    search: np.ndarray
    trav: np.ndarray
    marks: np.ndarray
    counts: np.ndarray
    synced: np.ndarray
    cells_r: np.ndarray
    cells_c: np.ndarray
    least_gap: np.ndarray
