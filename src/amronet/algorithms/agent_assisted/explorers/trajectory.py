"""Agents that follow given paths (``agents.trajectories``): a replayed or planned mission instead of exploration.

:class:`PathFollower` takes the place of the scenario's explorer when the scenario gives paths
(:class:`~amronet.world.trajectories.AgentPaths`); agents without a path are steered by that explorer as before.
It is not in :data:`~amronet.algorithms.agent_assisted.explorers.EXPLORERS`: it needs the paths, which only the loop
can read.

Per step, for each agent with a path, from the run's clock, the agent's own position and its own sonar:

* **Passing a waypoint**: the agent is within ``tolerance`` of its current waypoint — its own diameter, so that
  a body no bigger than the agent standing on the waypoint (a base station's node, a router, another agent) does
  not keep it from passing — and the waypoint's time has come (``t >= t_j``); it then heads for the next one.
  Several waypoints may be passed in one step (repeated points, a late agent).
* **Keeping to the schedule**: the agent drives at its waypoint at the speed that arrives at ``t_j``
  (``distance / (t_j - t)``), never faster than its ``max_speed``, and in the last step before ``t_j`` at the speed
  that lands on it. So it is never early: an agent that is on time follows the path as the file has it, in time
  (a waypoint repeated with a later time is a wait there). A path faster than the agent's speed limit makes it
  late: it drives at ``max_speed`` until it has caught up; the largest delay at a waypoint is reported
  (``path_late_max_s``).
* **Straight, with a sidestep**: it heads straight for the waypoint, but when its sonar sees something in its
  forward half nearer than ``avoid_range`` and nearer than the waypoint, it blends the waypoint's direction with
  the direction away from it (the rule routers driving to a goal use), so it slips past a body or a corner on
  the way.
* **After the last waypoint** the agent stops (speed 0) and is settled: a replayed mission ends where its path
  ends. The run ends when every path has ended (and the routers on their way to a goal have arrived).
* **Blocked**: the engine's collision rules hold as for every robot (a move into a wall or a body is refused).
  After a refused move the agent tries half the step (then a quarter, ...) so that it can come up to a wall it
  touches; an agent that has made no real progress (a quarter of the step it planned) toward its waypoint for
  ``give_up_s`` seconds skips that waypoint, and the overdue ones right after it that are no farther away
  (counted, ``path_waypoints_missed``). It never gets stuck for good: the worst a blocked path does is end early.

Headings set here may be overridden afterwards by the controller's safety rules (a tethered agent turns back to
its reference; an agent backing up for a reverse drop); the no-progress rule then skips what it cannot reach.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from amronet.algorithms.agent_assisted.explorers.base import Explorer
from amronet.engine.sensing import beam_angles

if TYPE_CHECKING:
    from amronet.world.trajectories import AgentPaths

__all__ = ["PathFollower"]

GIVE_UP_S = 5.0
"""Seconds without progress toward a waypoint after which an agent skips it."""
MIN_PROGRESS = 0.25
"""Progress per step, as a fraction of the step planned, that counts as not blocked."""
MAX_HALVINGS = 12
"""At most this many halvings of the step after refused moves in a row."""


def _escape(heading: np.ndarray, scans: np.ndarray, reach: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Escape headings from what each agent's sonar sees nearer than its own ``reach`` (go-to-goal's rule).

    Each reading ``r < reach`` pushes with weight ``(reach - r) / reach`` away from its beam; an agent is alarmed
    when a beam in its forward half sees something (:func:`~amronet.engine.motion.avoidance_heading`, with a reach
    per agent: what lies beyond the waypoint is no reason to turn).

    Args:
        heading: The agents' headings ``(M,)`` (those the scans were taken with).
        scans: Their sonar readings ``(M, n_beams)``.
        reach: How far each agent looks ``(M,)``.

    Returns:
        ``(escape, alarmed)``, both ``(M,)``.
    """
    angles = beam_angles(scans.shape[1])
    r = np.maximum(reach, 1e-9)[:, None]
    w = np.clip((r - scans) / r, 0.0, 1.0)
    a = heading[:, None] + angles[None, :]
    px = -(w * np.cos(a)).sum(axis=1)
    py = -(w * np.sin(a)).sum(axis=1)
    alarmed = ((w > 0) & (np.cos(angles) > 1e-9)[None, :]).any(axis=1)
    escape = np.where(alarmed & (np.hypot(px, py) < 1e-9), heading + np.pi, np.arctan2(py, px))
    return escape, alarmed


class PathFollower(Explorer):
    """Steer agents along given paths, the others by a fallback explorer (see the module docstring).

    Args:
        paths: The agents' paths; agent ``a`` of ``paths`` is the ``a``-th agent passed to :meth:`steer`.
        fallback: The scenario's explorer, for the agents without a path.
        dt: Step length, seconds.
        max_speed: Each agent's top speed ``(A,)`` (m/s).
        radius: Each agent's body radius ``(A,)`` (m); an agent has reached a waypoint within twice that.
        give_up_s: Seconds without progress after which a waypoint is skipped.
    """

    def __init__(self, paths: AgentPaths, fallback: Explorer, dt: float, max_speed: np.ndarray,
                 radius: np.ndarray, give_up_s: float = GIVE_UP_S) -> None:
        super().__init__(fallback.turn_noise, fallback.avoid_range, dt, fallback.r_c, fallback.extent)
        self.paths = paths
        self.fallback = fallback
        self.max_speed = np.broadcast_to(np.asarray(max_speed, dtype=float), (paths.n_agents,)).copy()
        self.tolerance = 2.0 * np.broadcast_to(np.asarray(radius, dtype=float), (paths.n_agents,))
        """Distance within which an agent has reached a waypoint: its diameter ``(A,)``."""
        self.give_up_s = give_up_s
        self.has_path = paths.has_path
        self.explorers = np.flatnonzero(~self.has_path)
        """Positions (in the agents passed to :meth:`steer`) of the agents the fallback explorer steers."""
        a = paths.n_agents
        self.next = paths.start[:-1].copy()
        """Each agent's current waypoint (a row of ``paths``); ``start[a + 1]`` once its path has ended."""
        self.end = paths.start[1:].copy()
        self.reached = np.zeros(a, dtype=np.int64)
        self.missed = np.zeros(a, dtype=np.int64)
        self.late_max = np.zeros(a)
        self.refused_moves = np.zeros(a, dtype=np.int64)
        self._stuck_s = np.zeros(a)
        self._halvings = np.zeros(a, dtype=np.int64)
        self._planned = np.zeros(a)
        """The step each agent planned last time, before halving (metres)."""
        self._asked = np.zeros(a)
        """The step each agent asked for last time, after halving (metres)."""
        self._last_d = np.full(a, np.inf)
        self._speed = np.zeros(a)
        self._steps = 0

    @property
    def following(self) -> np.ndarray:
        """Which agents are still on their path ``(A,)`` (``False`` for agents without one)."""
        return self.has_path & (self.next < self.end)

    def active(self, m: int) -> np.ndarray:
        """Agents that keep the run going: those still on their path.

        The mission is the paths: agents without one explore while it lasts but do not make it last.
        """
        return self.following.copy()

    def speed(self, max_speed: np.ndarray) -> np.ndarray:
        """Speeds of the last step: the path's pace for agents on a path, 0 after its end, top speed for the rest."""
        return np.where(self.has_path, self._speed, max_speed)

    def report(self) -> dict[str, object]:
        """How the paths were followed (the summary's ``mission``)."""
        return {"path_agents": int(np.count_nonzero(self.has_path)),
                "path_waypoints": len(self.paths.t),
                "path_waypoints_reached": int(self.reached.sum()),
                "path_waypoints_missed": int(self.missed.sum()),
                "path_finished_agents": int(np.count_nonzero(self.has_path & ~self.following)),
                "path_late_max_s": round(float(self.late_max.max(initial=0.0)), 9),
                "path_refused_moves": int(self.refused_moves.sum())}

    def steer(self, heading: np.ndarray, who: np.ndarray, scans: np.ndarray, sensor_range: float,  # noqa: D102
              refused: np.ndarray, rng: np.random.Generator, xy: np.ndarray, deployed_xy: np.ndarray) -> None:
        if len(who) != self.paths.n_agents:
            raise ValueError(f"{len(who)} agents but paths for {self.paths.n_agents}")
        t = self._steps * self.dt  # called once per step from t = 0: the loop's own clock, bit for bit
        self._steps += 1
        if len(self.explorers):
            e = self.explorers
            self.fallback.steer(heading, who[e], scans[e], sensor_range, refused[e], rng, xy, deployed_xy)
        p = xy[who]
        self._book_last_move(p, np.asarray(refused, dtype=bool), t)
        self._pass_waypoints(p, t)
        self._aim(heading, who, p, t, scans, min(sensor_range, self.avoid_range))

    # -- the parts of a step ---------------------------------------------------------------------------------
    def _distance(self, p: np.ndarray) -> np.ndarray:
        """Distance of each agent to its current waypoint (inf when it has none)."""
        on = self.following
        d = np.full(len(p), np.inf)
        d[on] = np.linalg.norm(self.paths.xy[self.next[on]] - p[on], axis=1)
        return d

    def _book_last_move(self, p: np.ndarray, refused: np.ndarray, t: float) -> None:
        """Refused moves, halvings, the no-progress clock; skip waypoints after ``give_up_s`` without progress.

        With the waypoint given up, so are the ones right after it that are overdue and no farther away (a stretch
        of path through something the agent cannot enter costs ``give_up_s`` once, not once per waypoint).
        """
        tried = self.following & (self._asked > 0) & (self._last_d > self.tolerance)  # not those waiting there
        blocked = tried & refused
        self.refused_moves += blocked
        self._halvings = np.where(blocked, np.minimum(self._halvings + 1, MAX_HALVINGS), 0)
        d = self._distance(p)
        stalled = tried.copy()
        stalled[tried] = self._last_d[tried] - d[tried] < MIN_PROGRESS * self._planned[tried]
        self._stuck_s = np.where(stalled, self._stuck_s + self.dt, 0.0)
        skip = stalled & (self._stuck_s >= self.give_up_s - 1e-9)
        if not skip.any():
            return
        bound = d + self.tolerance
        for _ in range(len(self.paths.t) + 1):
            self.missed += skip
            self.next[skip] += 1
            self._restart(skip)
            skip &= self.following
            skip[skip] &= self.paths.t[self.next[skip]] <= t + 1e-9
            skip &= self._distance(p) <= bound
            if not skip.any():
                return

    def _pass_waypoints(self, p: np.ndarray, t: float) -> None:
        """Move on past every waypoint an agent is at whose time has come."""
        tol = self.tolerance
        for _ in range(len(self.paths.t) + 1):
            d = self._distance(p)
            due = self.following & (d <= tol)
            due[due] &= self.paths.t[self.next[due]] <= t + 1e-9
            if not due.any():
                return
            self.late_max[due] = np.maximum(self.late_max[due], t - self.paths.t[self.next[due]])
            self.reached += due
            self.next[due] += 1
            self._restart(due)

    def _restart(self, who: np.ndarray) -> None:
        """Agents ``who`` (a mask) have a new waypoint: no history toward it."""
        self._stuck_s[who] = 0.0
        self._halvings[who] = 0
        self._last_d[who] = np.inf

    def _aim(self, heading: np.ndarray, who: np.ndarray, p: np.ndarray, t: float, scans: np.ndarray,
             reach: float) -> None:
        """Head for the current waypoint at the pace of the schedule, sidestepping; stop after the path's end."""
        on = self.following
        d = self._distance(p)
        speed = np.zeros(len(p))
        if on.any():
            goal = self.paths.xy[self.next[on]]
            delta = goal - p[on]
            turn = d[on] > 1e-12
            mine = who[on][turn]
            want = np.arctan2(delta[turn, 1], delta[turn, 0])
            escape, alarm = _escape(heading[mine], scans[on][turn], np.minimum(reach, d[on][turn]))
            heading[mine] = np.where(alarm, np.arctan2(np.sin(want) + np.sin(escape), np.cos(want) + np.cos(escape)),
                                     want)
            remaining = self.paths.t[self.next[on]] - t
            pace = d[on] / np.where(remaining > self.dt, remaining, self.dt)
            speed[on] = np.minimum(pace, self.max_speed[on])
        self._last_d = d
        self._planned = speed * self.dt
        self._speed = speed * 0.5 ** self._halvings
        self._asked = self._speed * self.dt
