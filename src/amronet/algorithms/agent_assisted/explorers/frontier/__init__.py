"""Frontier exploration for agents that release routers (Yamauchi-style, on a map shared by all agents).

The agents of a run build one coarse **knowledge grid** together from what they sense, and each drives along
a shortest path on it to the place where going soonest makes the covered area grow. Nothing here reads the
map's cells: only the agents' sonar readings and poses, and the positions of the deployed nodes that the
AMRoNet reports, all shared among the agents of the run.

Knowledge grid
    A grid over the area's bounding box at ``resolution`` metres (0.25 by default); each cell is *unknown*
    (no beam reached it yet), *free* or *occupied*. Every step, every beam of every agent marks the cells it
    crosses before its reading as free and, when it reads less than the sonar's maximum range, the cell at the
    reading as occupied. Evidence is counted per cell (a hit adds :data:`HIT_GAIN`, a pass removes 1, clamped
    to ``[-FREE_FLOOR, OCCUPIED_CAP]``) and a cell is occupied while its count is positive: walls, hit again
    and again, stay occupied when a beam grazes them, and a robot in transit that was seen once is cleared
    once beams pass where it stood. Readings that end on a robot the agents know of — another agent (the
    agents share their poses) or a deployed node (the AMRoNet reports them) — mark no obstacle.

Traversable cells
    Free cells with no occupied cell centre within ``clearance`` metres of their centre (the body inflated),
    and none of whose centre lies within ``clearance`` of a deployed node (routers are thin but may stand in
    a doorway). Near its own position an agent may also cross free cells that are not traversable, to get
    out of them; when no target can be reached around the deployed nodes, an agent plans through them and
    squeezes past with its sonar.

Targets, and which one: what makes coverage grow
    A deployed node *covers* the cells whose centre lies within ``(1 - cover_margin) r_c`` of it. Agents
    release a router when they are about to lose their last reference, i.e. where they go beyond the covered
    area, so coverage grows exactly when an agent enters uncovered space. A *target* is a traversable cell not
    yet visited that is

    * :data:`UNCOVERED`: an uncovered cell that the agents have seen (free or occupied: coverage counts
      free space right up to the walls) lies within ``window`` cells, itself included; or else
    * :data:`FRONTIER`: a frontier cell (a free cell with an unknown 4-neighbour) lies within ``window``
      cells: what lies beyond may lead to uncovered space.

    A target's score is the length of the shortest path to it (in cells) plus ``gap_weight`` times the
    straight-line distance from it to the nearest uncovered cell (in cells): an estimate of the way to new
    coverage through it. So an agent heads for the nearest uncovered place it knows a way to, but explores a
    frontier first when that frontier is the better bet (a corridor leading on toward uncovered space), and
    rooms deep in covered space come last. An agent that reaches an uncovered target whose own centre is
    covered then drives straight at the nearest seen uncovered cell for at most ``approach_time`` seconds,
    until a move is refused (it touches the wall) or the cell is covered: this covers the slivers along walls
    that no traversable cell reaches. A target an agent reached, or gave up on, is *visited* and never a
    target again: an agent that reached uncovered space without releasing a router was near enough to a
    reference after all, and a frontier it stood on is as resolved as the sonar can resolve it.

Planning
    Each agent plans with a breadth-first search over traversable cells (8-connected, a diagonal step only
    when both cells beside it are traversable: no corner cutting; neighbours in a fixed order and the first
    of equal scores wins, so ties break deterministically) from its own cell to the best-scoring target that
    no other agent has claimed (no other agent's goal within ``claim_radius``), or to the best claimed one
    when all are claimed; the search stops as soon as no cell farther out could score better. The agent keeps
    the path and replans when it reaches its goal, the goal stops being a target, a cell of the rest of the
    path stops being traversable, a node was deployed (the scores change), every ``replan_every`` seconds,
    and when it has stayed within :data:`STUCK_RADIUS` of one point for ``stuck_after`` seconds (the goal is
    then given up).

Driving
    An agent heads for the farthest of the next ``lookahead`` path cells it sees in a straight line over
    traversable cells, turned as little as needed (in steps of 15 degrees) to keep a lane of half-width
    ``lane`` clear of the sonar readings nearer than ``avoid_range`` — the routers, agents and corners the
    coarse grid misses; when no lane is clear it takes the escape heading of
    :func:`amronet.engine.motion.escape_one`. After a refused move it takes a uniform random heading for that
    step, as the random explorer does. An agent with no reachable target explores at random
    (:class:`amronet.algorithms.agent_assisted.explorers.RandomExplorer`) and tries to plan again every ``replan_every``
    seconds.

Only the run's generator is used (fresh headings and the random fallback), so a run is deterministic.

Modules: :mod:`~amronet.algorithms.agent_assisted.explorers.frontier.knowledge` (the grid, its update kernels,
traversable
cells), :mod:`~amronet.algorithms.agent_assisted.explorers.frontier.distance` (distances to uncovered space),
:mod:`~amronet.algorithms.agent_assisted.explorers.frontier.planning` (targets and the search),
:mod:`~amronet.algorithms.agent_assisted.explorers.frontier.navigation` (the per-step kernel: replanning and steering),
:mod:`~amronet.algorithms.agent_assisted.explorers.frontier.state` (the agents' plans and the kernel's named inputs) and
:mod:`~amronet.algorithms.agent_assisted.explorers.frontier.explorer` (the registered explorer).
"""

from amronet.algorithms.agent_assisted.explorers.frontier.distance import gap_to_uncovered
from amronet.algorithms.agent_assisted.explorers.frontier.explorer import FrontierExplorer, FrontierTuning
from amronet.algorithms.agent_assisted.explorers.frontier.knowledge import (
    FREE_FLOOR,
    HIT_GAIN,
    OCCUPIED_CAP,
    KnowledgeGrid,
)
from amronet.algorithms.agent_assisted.explorers.frontier.planning import FRONTIER, UNCOVERED
from amronet.algorithms.agent_assisted.explorers.frontier.state import REPLAN_REASONS, STUCK_RADIUS, AgentPlans

__all__ = [
    "FREE_FLOOR",
    "FRONTIER",
    "HIT_GAIN",
    "OCCUPIED_CAP",
    "REPLAN_REASONS",
    "STUCK_RADIUS",
    "UNCOVERED",
    "AgentPlans",
    "FrontierExplorer",
    "FrontierTuning",
    "KnowledgeGrid",
    "gap_to_uncovered",
]
