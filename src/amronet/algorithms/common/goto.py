"""Go-to-goal for deploying routers: drive to a goal point without losing given anchors, give up when blocked.

Used by the triangular deployment (self-spreading and agent-assisted): a router drives to its goal with
obstacle avoidance (:func:`amronet.engine.motion.go_to_goal`'s blend of goal and escape directions), never makes a
move that would take it farther than ``r_keep`` from one of its anchors (the two references it bridges) unless
it is already farther and the move brings it closer, and stops where it is once it has made no real progress
for ``give_up_steps`` steps in a row — the paper's "obstacle that cannot be avoided in few steps".
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numba import njit

from amronet.algorithms.common.link_quality import anchor_margins
from amronet.engine.motion import escape_one
from amronet.engine.sensing import beam_angles
from amronet.engine.table import NeighbourTable

__all__ = ["GoalSteering", "Steering", "goal_ends", "steer_one", "steering_of"]


class Steering(NamedTuple):
    """The go-to-goal state the kernels read and keep (:class:`GoalSteering`'s arrays, changed in place)."""

    goal: np.ndarray
    """``(N, 2)``: each robot's goal."""
    anchors: np.ndarray
    """``int64 (N, n_anchors)``: the nodes a move must not take it away from (-1: none)."""
    last_to_goal: np.ndarray
    """``(N,)``: its distance to the goal at its last step."""
    blocked_steps: np.ndarray
    """``int64 (N,)``: its steps in a row without progress."""
    give_up_steps: int
    """A robot stops after this many steps in a row without progress."""
    min_progress: float
    """Progress per step, as a fraction of the step length, that counts as not blocked."""


def steering_of(steering: GoalSteering) -> Steering:
    """The kernels' :class:`Steering` of ``steering``: its arrays, not copies (valid until it grows)."""
    return Steering(steering.goal, steering.anchors, steering.last_to_goal, steering.blocked_steps,
                    int(steering.give_up_steps), float(steering.min_progress))


@njit(cache=True, inline="always")
def _progress(i, xy, steering, max_step):  # pragma: no cover - numba
    """Robot ``i``'s way to its goal ``(gx, gy)``, its distance, and its steps without progress counting this one."""
    gx = steering.goal[i, 0] - xy[i, 0]
    gy = steering.goal[i, 1] - xy[i, 1]
    to_goal = math.hypot(gx, gy)
    blocked = (steering.blocked_steps[i] + 1
               if steering.last_to_goal[i] - to_goal < steering.min_progress * max_step else 0)
    return gx, gy, to_goal, blocked


@njit(cache=True)
def goal_ends(i, xy, steering, max_step):  # pragma: no cover - numba
    """Would :func:`steer_one` say robot ``i`` is done (arrived or given up) now? It changes nothing."""
    _, _, to_goal, blocked = _progress(i, xy, steering, max_step)
    return to_goal <= 1e-9 or blocked >= steering.give_up_steps


@njit(cache=True, inline="always")
def steer_one(i, xy, heading, steering, scans, angles, sensor_range, max_step, r_keep):  # pragma: no cover - numba
    """One go-to-goal step of robot ``i`` (heading set in place, ``steering`` kept): ``(step_length, done)``."""
    gx, gy, to_goal, blocked = _progress(i, xy, steering, max_step)
    if to_goal <= 1e-9:
        return 0.0, True
    steering.blocked_steps[i] = blocked
    steering.last_to_goal[i] = to_goal
    if blocked >= steering.give_up_steps:
        return 0.0, True
    want = math.atan2(gy, gx)
    escape, alarm = escape_one(heading[i], scans, angles, sensor_range)
    if alarm:
        want = math.atan2(math.sin(want) + math.sin(escape), math.cos(want) + math.cos(escape))
    heading[i] = want
    step = min(max_step, to_goal)
    nx = xy[i, 0] + step * math.cos(want)
    ny = xy[i, 1] + step * math.sin(want)
    anchors = steering.anchors
    for k in range(anchors.shape[1]):
        a = anchors[i, k]
        if a < 0:
            continue
        now = math.hypot(xy[i, 0] - xy[a, 0], xy[i, 1] - xy[a, 1])
        after = math.hypot(nx - xy[a, 0], ny - xy[a, 1])
        if after > max(now, r_keep):
            return 0.0, False
    return step, False


@njit(cache=True)
def _steer(who, xy, heading, steering, scans, angles, sensor_range, max_step, r_keep, length,
           done):  # pragma: no cover - numba
    for m in range(who.shape[0]):
        length[m], done[m] = steer_one(who[m], xy, heading, steering, scans[m], angles, sensor_range, max_step[m],
                                       r_keep)


class GoalSteering:
    """Goal-seeking state of every robot of a swarm (only the robots passed to :meth:`steer` are touched).

    Besides the goal and the anchors a move must not take it away from (in metres, :func:`steer_one`), a robot keeps
    its *references* (the anchors :meth:`start` gave it, the nodes whose links it must keep) and where its row of the
    neighbour table last held one of them, for :meth:`check_links`: the link test at settling under a radio whose
    links are not decided by distance alone.

    Args:
        n: Number of robots.
        n_anchors: Anchors per robot.
        give_up_steps: Consecutive steps without progress after which a robot stops.
        min_progress: Progress per step, as a fraction of the step length, that counts as not blocked.
    """

    def __init__(self, n: int, n_anchors: int, give_up_steps: int, min_progress: float = 0.25) -> None:
        self.goal = np.zeros((n, 2))
        self.anchors = np.full((n, n_anchors), -1, dtype=np.int64)
        self.last_to_goal = np.full(n, np.inf)
        self.blocked_steps = np.zeros(n, dtype=np.int64)
        self.give_up_steps = give_up_steps
        self.min_progress = min_progress
        self.refs = np.full((n, n_anchors), -1, dtype=np.int64)
        """The nodes each robot must hear where it settles (:meth:`check_links`; -1: none)."""
        self.heard_xy = np.full((n, 2), np.nan)
        """Where each robot's table row last held one of its :attr:`refs` (``nan``: not yet)."""
        self.retreating = np.zeros(n, dtype=np.bool_)
        """Robots driving back to :attr:`heard_xy` after they would have settled out of touch."""

    def start(self, who: np.ndarray, goal: np.ndarray, anchors: np.ndarray) -> None:
        """Give robots ``who`` new goals ``(M, 2)`` and anchors ``(M, n_anchors)`` (-1: none), also their references."""
        self.goal[who] = goal
        self.anchors[who] = anchors
        self.last_to_goal[who] = np.inf
        self.blocked_steps[who] = 0
        self.refs[who] = anchors
        self.heard_xy[who] = np.nan
        self.retreating[who] = False

    def grow(self, n_new: int) -> None:
        """Make room for ``n_new`` robots added at the end (routers released), with no goal and no anchors."""

        def pad(a: np.ndarray, fill: float | int | bool) -> np.ndarray:
            return np.concatenate([a, np.full((n_new, *a.shape[1:]), fill, dtype=a.dtype)])

        self.goal, self.anchors = pad(self.goal, 0.0), pad(self.anchors, -1)
        self.last_to_goal, self.blocked_steps = pad(self.last_to_goal, np.inf), pad(self.blocked_steps, 0)
        self.refs, self.heard_xy, self.retreating = pad(self.refs, -1), pad(self.heard_xy, np.nan), pad(
            self.retreating, False)

    def steer(
        self,
        who: np.ndarray,
        xy: np.ndarray,
        heading: np.ndarray,
        scans: np.ndarray,
        sensor_range: float,
        max_step: np.ndarray,
        r_keep: float,
    ) -> tuple[np.ndarray, np.ndarray]:
        """Set the headings of robots ``who`` (in place) and return ``(step_length, done)`` for each.

        ``done`` robots have arrived or given up; their step length is 0.
        """
        m = len(who)
        length = np.zeros(m)
        done = np.zeros(m, dtype=np.bool_)
        if m:
            _steer(np.asarray(who, dtype=np.int64), xy, heading, steering_of(self),
                   np.ascontiguousarray(scans, dtype=float), beam_angles(scans.shape[1]), float(sensor_range),
                   np.ascontiguousarray(max_step, dtype=float), float(r_keep), length, done)
        return length, done

    def check_links(self, who: np.ndarray, done: np.ndarray, table: NeighbourTable,
                    xy: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The link test at settling: may the robots ``who`` that are ``done`` (:meth:`steer`) settle where they are?

        Reads only each robot's own row of ``table`` (does it hear one of its :attr:`refs`?) and its own position.
        A robot that hears one is remembered there (:attr:`heard_xy`). A ``done`` robot that hears none does not
        settle: the first time, it drives back to where it last heard one (a fresh goal without metre anchors: the
        medium, not the distance, says where the link holds); one that hears none after that retreat, or never
        heard one, is *lost*. Call it once per step with the robots steered in that step.

        Returns:
            ``(settle, lost)``, masks aligned with ``who``: the robots that may settle, and the lost ones (the caller
            decides what they do). The robots sent back are in neither.
        """
        who = np.asarray(who, dtype=np.int64)
        heard = np.isfinite(anchor_margins(table, who, self.refs[who])).any(axis=1)
        self.heard_xy[who[heard]] = xy[who[heard]]
        bad = done & ~heard
        back = bad & ~self.retreating[who] & ~np.isnan(self.heard_xy[who, 0])
        for i in who[back]:
            goal, refs = self.heard_xy[i].copy(), self.refs[i].copy()
            self.start(np.array([i]), goal[None], np.full((1, self.anchors.shape[1]), -1, dtype=np.int64))
            self.refs[i], self.heard_xy[i], self.retreating[i] = refs, goal, True
        return done & heard, bad & ~back
