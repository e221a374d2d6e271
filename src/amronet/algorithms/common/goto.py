"""Go-to-goal for deploying routers: drive to a goal point without losing given anchors, give up when blocked.

Used by the triangular deployment (self-spreading and agent-assisted): a router drives to its goal with
obstacle avoidance (:func:`amronet.engine.motion.go_to_goal`'s blend of goal and escape directions), never makes a
move that would take it farther than ``r_keep`` from one of its anchors (the two references it bridges) unless
it is already farther and the move brings it closer, and stops where it is once it has made no real progress
for ``give_up_steps`` steps in a row — the paper's "obstacle that cannot be avoided in few steps".
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from amronet.engine.motion import escape_one
from amronet.engine.sensing import beam_angles

__all__ = ["GoalSteering", "goal_ends", "steer_one"]


@njit(cache=True, inline="always")
def _progress(i, xy, goal, last_to_goal, blocked_steps, min_progress, max_step):  # pragma: no cover - numba
    """Robot ``i``'s way to its goal ``(gx, gy)``, its distance, and its steps without progress counting this one."""
    gx = goal[i, 0] - xy[i, 0]
    gy = goal[i, 1] - xy[i, 1]
    to_goal = math.hypot(gx, gy)
    blocked = blocked_steps[i] + 1 if last_to_goal[i] - to_goal < min_progress * max_step else 0
    return gx, gy, to_goal, blocked


@njit(cache=True)
def goal_ends(i, xy, goal, last_to_goal, blocked_steps, give_up, min_progress, max_step):  # pragma: no cover - numba
    """Would :func:`steer_one` say robot ``i`` is done (arrived or given up) now? It changes nothing."""
    _, _, to_goal, blocked = _progress(i, xy, goal, last_to_goal, blocked_steps, min_progress, max_step)
    return to_goal <= 1e-9 or blocked >= give_up


@njit(cache=True, inline="always")
def steer_one(i, xy, heading, goal, anchors, scans, angles, sensor_range, max_step, r_keep, last_to_goal,
              blocked_steps, give_up, min_progress):  # pragma: no cover - numba
    """One go-to-goal step of robot ``i`` (heading set in place): ``(step_length, done)``."""
    gx, gy, to_goal, blocked = _progress(i, xy, goal, last_to_goal, blocked_steps, min_progress, max_step)
    if to_goal <= 1e-9:
        return 0.0, True
    blocked_steps[i] = blocked
    last_to_goal[i] = to_goal
    if blocked >= give_up:
        return 0.0, True
    want = math.atan2(gy, gx)
    escape, alarm = escape_one(heading[i], scans, angles, sensor_range)
    if alarm:
        want = math.atan2(math.sin(want) + math.sin(escape), math.cos(want) + math.cos(escape))
    heading[i] = want
    step = min(max_step, to_goal)
    nx = xy[i, 0] + step * math.cos(want)
    ny = xy[i, 1] + step * math.sin(want)
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
def _steer(who, xy, heading, goal, anchors, scans, angles, sensor_range, max_step, r_keep, last_to_goal,
           blocked_steps, give_up, min_progress, length, done):  # pragma: no cover - numba
    for m in range(who.shape[0]):
        length[m], done[m] = steer_one(who[m], xy, heading, goal, anchors, scans[m], angles, sensor_range,
                                       max_step[m], r_keep, last_to_goal, blocked_steps, give_up, min_progress)


class GoalSteering:
    """Goal-seeking state of every robot of a swarm (only the robots passed to :meth:`steer` are touched).

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

    def start(self, who: np.ndarray, goal: np.ndarray, anchors: np.ndarray) -> None:
        """Give robots ``who`` new goals ``(M, 2)`` and anchors ``(M, n_anchors)`` (-1: none)."""
        self.goal[who] = goal
        self.anchors[who] = anchors
        self.last_to_goal[who] = np.inf
        self.blocked_steps[who] = 0

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
            _steer(np.asarray(who, dtype=np.int64), xy, heading, self.goal, self.anchors,
                   np.ascontiguousarray(scans, dtype=float), beam_angles(scans.shape[1]), float(sensor_range),
                   np.ascontiguousarray(max_step, dtype=float), float(r_keep), self.last_to_goal,
                   self.blocked_steps, self.give_up_steps, self.min_progress, length, done)
        return length, done
