"""``strip-goals``: the paper's section 6 thought experiment — greedy drops, then each router drives to an r-strip goal.

The paper (section 6) asks whether agents could place routers on the static r-strip pattern (Bai et al., the
fewest nodes per area for coverage with connectivity, :mod:`amronet.patterns`) instead of where the greedy rule
puts them, and argues they cannot reach its count: routers are slow, obstacles block goal points, the lattices
grown from several base stations do not line up, and agents go where they go. This rule makes the experiment
concrete, with only what a location-aware team knows (the positions of the base stations and of the relays it
put down; never the map):

* **When**: the paper's greedy rule (``last-reference``): an agent about to lose its last reference drops a
  router next to itself.
* **Where it goes**: the router then drives to the nearest *free* goal point of the r-strip lattice anchored at
  the base station whose status it takes — rows of nodes ``s`` apart, rows ``(1 + sqrt(3)/2) s`` apart with odd
  rows shifted by ``s/2``, and between two rows a *connector* ``0.966 s`` from a node of each (at every column:
  the static pattern needs one per pair of rows, but a team growing the lattice from one side does not know where
  the others will be needed). ``s = spacing * r_c`` (default ``0.999 r_c``: the static pattern's ``r_c``, less a
  millimetre or so that floating point does not cut links that are exactly ``r_c`` long).
* Only goal points within ``s`` of the reference the router was put down next to count, so that it stays
  linked to it on its way (it never moves farther from it than that, or than it already is) and once there. Row
  points come first, by distance from where the router was put down; a connector only when no row point is free.
  A goal point is free when no node and no other router's goal lies within ``free_radius * s`` of it.
* A router that finds no free goal point stays where it was put down; one that is blocked on its way (a goal in a
  wall, or behind one: the team does not know the map) stops where it is after the steering's give-up steps.
  Either way it then serves as a reference like a router put down by the greedy rule. While it drives it relays
  but serves as no reference (as a triangle router): an agent that took it for its reference would put its next
  router down next to a node that is leaving, and be cut off when it has left (a first version did, and agents
  were cut off in 16-20 of 20 runs per building on the unit disk). An agent about to lose its last deployed
  reference whose router drives off therefore turns back, as a tethered agent does, and puts down another at the
  next step, until one finds no free goal and stays next to it: then it goes on.

Triangular deployment and its optimizations work unchanged (triangle routers are the controller's). The rule
reads positions (``reads_positions``), as the greedy rule does.
"""

from __future__ import annotations

import math
from typing import Annotated

import numpy as np
from pydantic import BaseModel, ConfigDict, Field

from amronet.algorithms.agent_assisted.drops.base import DROP_RULES
from amronet.algorithms.agent_assisted.drops.last_reference import LastReference

__all__ = ["StripGoals", "StripGoalsParams", "strip_goal_points"]

ROW_GAP = 1.0 + math.sqrt(3.0) / 2.0
"""Distance between two rows of the r-strip, in units of the spacing (Bai et al.)."""


class StripGoalsParams(BaseModel):
    """Parameters of the strip-goals rule.

    Attributes:
        spacing: The lattice's link length ``s`` as a fraction of ``r_c``.
        free_radius: A goal point is taken when a node or another router's goal lies within this fraction of ``s``.
        retries: Further goals a router blocked on its way tries (each the nearest free one from where it stopped).
    """

    model_config = ConfigDict(extra="forbid", frozen=True)

    spacing: Annotated[float, Field(strict=True, gt=0.5, le=1, allow_inf_nan=False)] = 0.999
    free_radius: Annotated[float, Field(strict=True, gt=0, lt=1, allow_inf_nan=False)] = 0.5
    retries: Annotated[int, Field(strict=True, ge=0, le=10)] = 2


def strip_goal_points(origin: np.ndarray, s: float, centre: np.ndarray, radius: float) -> tuple[np.ndarray, np.ndarray]:
    """The r-strip lattice's goal points within ``radius`` of ``centre``: row points and connectors.

    Row ``j`` lies at ``y = origin_y + j h`` (``h = (1 + sqrt(3)/2) s``) with points at
    ``x = origin_x + i s + (j mod 2) s / 2``; the connector of row point ``(i, j)`` sits at ``(x + s/4, y + h/2)``,
    ``0.966 s`` from it and from the nearest point of row ``j + 1``. The origin is a row point.

    Args:
        origin: The lattice's anchor ``(2,)`` (a base station).
        s: Link length.
        centre: Where to look ``(2,)``.
        radius: How far.

    Returns:
        ``(rows, connectors)``, each ``(K, 2)``.
    """
    h = ROW_GAP * s
    rel = np.asarray(centre, dtype=float) - np.asarray(origin, dtype=float)
    j = np.arange(math.floor((rel[1] - radius) / h) - 1, math.ceil((rel[1] + radius) / h) + 1)
    i = np.arange(math.floor((rel[0] - radius) / s) - 1, math.ceil((rel[0] + radius) / s) + 2)
    jj, ii = np.meshgrid(j, i, indexing="ij")
    x = ii * s + (jj % 2) * (s / 2)
    y = jj * h
    rows = np.stack([x.ravel(), y.ravel()], axis=1)
    connectors = rows + np.array([s / 4, h / 2])
    out = []
    for pts in (rows, connectors):
        d = np.hypot(pts[:, 0] - rel[0], pts[:, 1] - rel[1])
        out.append(pts[d <= radius] + origin)
    return out[0], out[1]


@DROP_RULES.register("strip-goals")
class StripGoals(LastReference):
    """Greedy drops; each router then drives to the nearest free r-strip goal point linked to its reference."""

    Params = StripGoalsParams
    params: StripGoalsParams
    drives_to_goal = True

    def goal(self, spot: np.ndarray, reference_xy: np.ndarray, origin_xy: np.ndarray,  # noqa: D102
             taken_xy: np.ndarray) -> np.ndarray | None:
        s = self.params.spacing * self.context.r_c
        for pts in strip_goal_points(origin_xy, s, reference_xy, self.keep_radius()):
            if len(pts) and len(taken_xy):
                near = np.hypot(pts[:, None, 0] - taken_xy[None, :, 0], pts[:, None, 1] - taken_xy[None, :, 1])
                pts = pts[(near >= self.params.free_radius * s).all(axis=1)]
            if len(pts):
                return pts[np.argmin(np.hypot(pts[:, 0] - spot[0], pts[:, 1] - spot[1]))]
        return None

    def retries(self) -> int:  # noqa: D102
        return self.params.retries

    def keep_radius(self) -> float:  # noqa: D102
        return self.params.spacing * self.context.r_c * (1.0 + 1e-9)  # lattice neighbours are exactly s apart
