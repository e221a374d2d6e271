"""Releasing routers: where an agent puts a router down, and the reference and triangle routers it releases.

Cold code: a handful of events per run. :class:`Releasing` is mixed into
:class:`~amronet.algorithms.agent_assisted.controller.AgentAssisted`; the names it declares are the controller's.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

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

__all__ = ["Releasing"]


def _pair_key(agent: int, ref_i: int, ref_j: int) -> tuple[int, int, int]:
    """The key of a triangle served by ``agent`` for the references ``ref_i`` and ``ref_j`` (either order)."""
    return (agent, min(ref_i, ref_j), max(ref_i, ref_j))


def _segments_clear(p: np.ndarray, ends: np.ndarray, r: float, xy: np.ndarray, radius: np.ndarray) -> np.ndarray:
    """Which segments ``p -> ends[m]`` a body of radius ``r`` can be carried along without touching a body."""
    seg = ends - p
    length2 = np.maximum(np.einsum("ij,ij->i", seg, seg), 1e-300)
    rel = xy - p
    t = np.clip((rel @ seg.T) / length2[None, :], 0.0, 1.0)
    closest = p[None, None, :] + t[:, :, None] * seg[None, :, :]
    d = np.linalg.norm(xy[:, None, :] - closest, axis=2)
    return (d >= r + radius[:, None]).all(axis=0)


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
        p = sw.xy[agent]
        ref = sw.xy[toward]
        r = self.router_model.radius
        gap = sw.radius[agent] + r + self.params.release_gap
        base = np.arctan2(ref[1] - p[1], ref[0] - p[0])
        others = np.delete(np.arange(len(sw)), agent)
        turns = np.array([0, 1, -1, 2, -2, 3, -3, 4, -4, 5, -5, 6]) * (np.pi / 6)
        cand = p + gap * np.stack([np.cos(base + turns), np.sin(base + turns)], axis=1)
        within = self.r_c if self.drop_rule.near_reference else np.inf
        ok = np.linalg.norm(cand - ref, axis=1) <= within
        ok &= self.path_clear(np.repeat(p[None], len(cand), axis=0), cand, np.full(len(cand), r))
        if len(others):
            d = np.linalg.norm(cand[:, None, :] - sw.xy[None, others, :], axis=2)
            ok &= (d >= r + sw.radius[others][None, :]).all(axis=1)
        hit = np.flatnonzero(ok)
        if len(hit):
            return cand[hit[0]]
        # farther out: the agent's own ring is full (other bodies, walls)
        turns = np.concatenate([[0.0], np.repeat(np.arange(1, 12), 2) * np.array([1.0, -1.0] * 11), [12.0]]) * (
            np.pi / 12)
        step = 2.0 * r + self.params.release_gap
        dirs = np.stack([np.cos(base + turns), np.sin(base + turns)], axis=1)
        cand = np.concatenate([p + (gap + k * step) * dirs for k in (1, 2)])
        ok = np.linalg.norm(cand - ref, axis=1) <= within
        ok[ok] &= self.path_clear(np.repeat(p[None], int(ok.sum()), axis=0), cand[ok], np.full(int(ok.sum()), r))
        if len(others) and ok.any():
            ok[ok] &= _segments_clear(p, cand[ok], r, sw.xy[others], sw.radius[others])
        hit = np.flatnonzero(ok)
        return cand[hit[0]] if len(hit) else None

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

