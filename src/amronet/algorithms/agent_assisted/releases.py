"""Releasing routers: where an agent puts a router down, and the reference and triangle routers it releases.

Cold code: a handful of events per run. :class:`Releasing` is mixed into
:class:`~amronet.algorithms.agent_assisted.controller.AgentAssisted`; the names it declares are the controller's.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numpy as np

from amronet.algorithms.agent_assisted.release_kernels import first_free_spot
from amronet.algorithms.common.triangular import triangle_goal
from amronet.engine.robots import Role, State

if TYPE_CHECKING:
    from collections.abc import Callable

    from amronet.algorithms.agent_assisted.drops import DropRule
    from amronet.algorithms.agent_assisted.params import AgentAssistedParams
    from amronet.algorithms.agent_assisted.relocate import Relocator
    from amronet.algorithms.agent_assisted.strip_driving import StripDrivers
    from amronet.algorithms.common.goto import GoalSteering
    from amronet.engine.robots import RobotModel, Swarm

__all__ = ["Releasing", "release_spot"]


def _pair_key(agent: int, ref_i: int, ref_j: int) -> tuple[int, int, int]:
    """The key of a triangle served by ``agent`` for the references ``ref_i`` and ``ref_j`` (either order)."""
    return (agent, min(ref_i, ref_j), max(ref_i, ref_j))


_NEAR_TURNS = np.array([0, 1, -1, 2, -2, 3, -3, 4, -4, 5, -5, 6]) * (np.pi / 6)
"""The agent's own ring: 12 directions from the reference's, nearest first."""
_FAR_TURNS = np.concatenate([[0.0], np.repeat(np.arange(1, 12), 2) * np.array([1.0, -1.0] * 11), [12.0]]) * (
    np.pi / 12)
"""The two farther rings: 24 directions from the reference's, nearest first."""
_TURNS = np.concatenate([_NEAR_TURNS, _FAR_TURNS, _FAR_TURNS])
"""Every candidate's direction from the reference's: the agent's ring, then the two farther rings."""
_RINGS = np.repeat([0.0, 1.0, 2.0], [len(_NEAR_TURNS), len(_FAR_TURNS), len(_FAR_TURNS)])
"""Every candidate's ring: its distance from the agent is ``gap + ring * step``."""


def _out_of_reach(p: np.ndarray, ref: np.ndarray, reach: float, within: float) -> bool:
    """Whether every point within ``reach`` of ``p`` is farther than ``within`` from ``ref``, rounding included.

    A candidate spot lies at most ``reach`` from ``p`` (up to the rounding of its coordinates), so its distance to
    ``ref`` is at least ``|p - ref| - reach``; the slack (a billionth of the coordinates' size, far above their
    rounding errors) keeps every spot the full search would take.
    """
    px, py, rx, ry = float(p[0]), float(p[1]), float(ref[0]), float(ref[1])
    slack = 1e-9 * (1.0 + abs(px) + abs(py) + abs(rx) + abs(ry) + reach)
    return math.hypot(rx - px, ry - py) - reach > within + slack


def release_spot(p: np.ndarray, ref: np.ndarray, gap: float, step: float, r: float, within: float,
                 path_clear: Callable[[np.ndarray, np.ndarray, np.ndarray], np.ndarray], xy: np.ndarray,
                 radius: np.ndarray, agent: int) -> np.ndarray | None:
    """Where the body at ``p`` puts a router down next to itself toward ``ref``; ``None`` when no spot is free.

    First the ring at ``gap`` (12 directions, nearest to the reference's first), then the two rings at ``gap +
    step`` and ``gap + 2 step`` (24 directions) whose straight line from the agent must also pass clear of every
    body. A spot must be within ``within`` of ``ref``, clear of walls along the way (``path_clear``, the agent's
    hand, asked once for every candidate) and clear of every body of ``xy``/``radius`` but ``agent``
    (:func:`~amronet.algorithms.agent_assisted.release_kernels.first_free_spot`).

    A reference farther than ``within`` beyond the farthest ring (an agent that strayed out of its reach) leaves
    no spot: the answer is ``None`` at once, the hand never asked (:func:`_out_of_reach`).
    """
    if _out_of_reach(p, ref, gap + 2.0 * step, within):
        return None
    angles = np.arctan2(ref[1] - p[1], ref[0] - p[0]) + _TURNS
    away = gap + _RINGS * step
    cand = np.empty((len(_TURNS), 2))
    cand[:, 0] = p[0] + away * np.cos(angles)
    cand[:, 1] = p[1] + away * np.sin(angles)
    clear = path_clear(np.repeat(p[None], len(cand), axis=0), cand, np.full(len(cand), r))
    k = first_free_spot(cand, clear, len(_NEAR_TURNS), float(p[0]), float(p[1]), float(ref[0]), float(ref[1]),
                        float(within), float(r), xy, radius, agent)
    return cand[k] if k >= 0 else None


class Releasing:
    """Putting routers down next to an agent: reference routers and triangle routers (a mixin of the controller)."""

    swarm: Swarm
    params: AgentAssistedParams
    r_c: float
    r_eff: float
    router_model: RobotModel
    path_clear: Callable[[np.ndarray, np.ndarray, np.ndarray], np.ndarray]
    drop_rule: DropRule
    agents: np.ndarray
    left: np.ndarray
    released: int
    released_by: np.ndarray
    settle_s: float
    settle_at: dict[int, float]
    strips: StripDrivers | None
    relocator: Relocator | None
    steering: GoalSteering
    disabled: np.ndarray
    moving_triangles: int
    triangles_released: list[tuple[int, int, int]]
    _served: set[tuple[int, int, int]]
    _grow: Callable[[int], None]
    _nodes_changed: Callable[[], None]

    def _release_spot(self, agent: int, toward: int) -> np.ndarray | None:
        """Where ``agent`` puts a router down, next to itself toward ``toward``; ``None`` when no spot is free.

        First the ring right next to the agent (12 directions, nearest to the reference's first), then two rings
        farther out (24 directions) whose straight line from the agent must also pass clear of every body. A
        spot must be within ``r_c`` of the reference, clear of walls along the way and clear of every body.
        """
        sw = self.swarm
        r = self.router_model.radius
        return release_spot(sw.xy[agent], sw.xy[toward], sw.radius[agent] + r + self.params.release_gap,
                            2.0 * r + self.params.release_gap, r,
                            self.r_c if self.drop_rule.near_reference else np.inf, self.path_clear, sw.xy,
                            sw.radius, agent)

    def _add_router(self, agent: int, toward: int, state: int) -> int | None:
        """Release a router from ``agent`` next to itself toward ``toward``; its index, or ``None`` (no free spot)."""
        sw = self.swarm
        spot = self._release_spot(agent, toward)
        if spot is None:
            return None
        new = sw.extend(self.router_model, Role.ROUTER, state, spot[None], np.array([sw.status[agent]]),
                        heading=np.array([sw.heading[agent]]))
        self._grow(len(new))
        if self.relocator is not None:  # the repair may keep how the router got here (repair: retrace)
            self.relocator.carried(int(new[0]), agent, sw)
        self._nodes_changed()
        self.left[agent] -= 1
        self.released += 1
        self.released_by[np.searchsorted(self.agents, agent)] += 1
        return int(new[0])

    def _release_reference(self, agent: int, current: int, t: float) -> int | None:
        """Put a reference router down (settling first for ``settle_s`` when set); its index, ``None``: no free spot.

        Under a rule whose routers drive on to a goal (``strip-goals``) it starts for its goal, once settled.
        """
        new = self._add_router(agent, current, State.REFERENCE if self.settle_s <= 0 else State.DROPPED)
        if new is None:
            return None
        if self.settle_s > 0:
            self.settle_at[new] = t + self.settle_s
            if self.strips is not None:
                self.strips.waiting[new] = current
        elif self.strips is not None:
            self.strips.start(new, current)
        return new

    def _release_triangle(self, agent: int, ref_i: int, ref_j: int) -> None:
        sw = self.swarm
        new = self._add_router(agent, ref_i, State.TRIANGLE)
        if new is None:
            return  # no free spot next to the agent: the pair is not served yet, tried again next step
        key = _pair_key(agent, ref_i, ref_j)
        self._served.add(key)
        self.triangles_released.append(key)
        self.moving_triangles += 1
        goal = triangle_goal(sw.xy[[ref_i]], sw.xy[[ref_j]], sw.xy[[agent]], self.r_eff)
        self.steering.start(np.array([new]), goal, np.array([[ref_i, ref_j]]))
        if self.params.triangular == "local":
            self.disabled[[new, ref_i, ref_j]] = True

