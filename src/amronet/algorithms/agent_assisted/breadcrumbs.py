"""The agents' odometry breadcrumbs that ``repair: retrace`` backs routers up along (:mod:`.retrace`).

Every agent keeps its own path as points sampled from its odometry, with loops erased: a point that comes within
:attr:`Breadcrumbs.erase` of an earlier point of the path cuts the path back to that earlier point (a loop-erased
walk). The points are one tree shared by all (a point keeps its predecessor), so a router holds only the point it
came from. Each agent's path is a row of one buffer with a length; one compiled kernel (:func:`record_points`) adds
the points of a step, or of a whole quiet stretch's steps, agent by agent.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

__all__ = ["Breadcrumbs", "record_points"]


@njit(cache=True)
def record_points(xy: np.ndarray, parent: np.ndarray, count: int, paths: np.ndarray, length: np.ndarray,
                  tip: np.ndarray, trail: np.ndarray, who: np.ndarray, spacing: float, erase: float) -> int:
    """The agents ``who`` at ``trail[s]`` ``(k, m, 2)``, for ``s`` in order, that have moved ``spacing`` add a point.

    Step by step, agent by agent: an agent whose position is at least ``spacing`` from its tip goes on to it, its
    path cut back to the first point within ``erase`` of it (its loop erased); the new point follows the path's last
    point and is the agent's new path end and tip. ``xy``, ``parent``, ``paths``, ``length`` and ``tip`` are updated
    in place and must have room for ``k`` new points per agent.

    Args:
        xy: The points ``(capacity, 2)``.
        parent: Each point's predecessor ``(capacity,)`` (-1: none).
        count: Points so far.
        paths: Per agent, the points of its path from its start ``(m, path capacity)``.
        length: Per agent, its path's length ``(m,)``.
        tip: Per agent, its newest point ``(m,)``.
        trail: The agents' positions step by step ``(k, m, 2)``.
        who: Which agents record ``(m,)``.
        spacing: How far an agent moves from its tip before it adds a point, metres (0: it always adds one).
        erase: A new point within this distance of an earlier point of the path cuts the path back to it, metres.

    Returns:
        The number of points now.
    """
    for s in range(trail.shape[0]):
        for m in range(trail.shape[1]):
            if not who[m]:
                continue
            x = trail[s, m, 0]
            y = trail[s, m, 1]
            t = tip[m]
            if not math.hypot(x - xy[t, 0], y - xy[t, 1]) >= spacing:
                continue
            n = length[m]
            for i in range(n):
                q = paths[m, i]
                if math.hypot(xy[q, 0] - x, xy[q, 1] - y) < erase:
                    n = i + 1
                    break
            xy[count, 0] = x
            xy[count, 1] = y
            parent[count] = paths[m, n - 1]
            paths[m, n] = count
            length[m] = n + 1
            tip[m] = count
            count += 1
    return count


class Breadcrumbs:
    """Sampled, loop-erased paths of the agents, and the routers' ways, as one tree of points.

    Args:
        xy: The agents' start positions ``(m, 2)`` (the roots of their paths).
        spacing: An agent's path gains a point once it is this far from the path's newest point, metres.
        erase: A new point within this distance of an earlier point of the path cuts the path back to it, metres.
    """

    def __init__(self, xy: np.ndarray, spacing: float, erase: float) -> None:
        self.spacing = spacing
        self.erase = erase
        self.xy = np.zeros((max(64, 4 * len(xy)), 2))
        self.parent = np.full(len(self.xy), -1, dtype=np.int64)
        self.count = 0
        self._paths = np.zeros((len(xy), 64), dtype=np.int64)
        """Per agent, the points of its loop-erased path, from its start (the first :attr:`length` of its row)."""
        self.length = np.ones(len(xy), dtype=np.int64)
        """Per agent, its path's length (at least 1: its start)."""
        self._paths[:, 0] = self.add_many(np.asarray(xy, dtype=float).reshape(-1, 2), np.full(len(xy), -1))
        self.tip = self._paths[:, 0].copy()
        """Per agent, the newest point of its path."""

    @property
    def paths(self) -> list[np.ndarray]:
        """Per agent, the points of its loop-erased path, from its start (copies)."""
        return [self._paths[m, :n].copy() for m, n in enumerate(self.length)]

    @property
    def path_rows(self) -> np.ndarray:
        """The paths' rows ``(A, L)``, the first :attr:`length` of each (the array itself: a quiet stretch keeps it)."""
        return self._paths

    def _room(self, k: int) -> None:
        """Make room for ``k`` more points."""
        while self.count + k > len(self.xy):
            self.xy = np.concatenate([self.xy, np.zeros_like(self.xy)])
            self.parent = np.concatenate([self.parent, np.full(len(self.parent), -1, dtype=np.int64)])

    def _path_room(self, n: int) -> None:
        """Make room for paths of ``n`` points."""
        while n > self._paths.shape[1]:
            self._paths = np.concatenate([self._paths, np.zeros_like(self._paths)], axis=1)

    def add(self, p: np.ndarray, parent: int) -> int:
        """A new point at ``p`` that follows ``parent`` (-1: none); its index."""
        self._room(1)
        k = self.count
        self.xy[k] = p
        self.parent[k] = parent
        self.count += 1
        return k

    def add_many(self, p: np.ndarray, parent: np.ndarray) -> np.ndarray:
        """New points at ``p`` ``(k, 2)`` that follow ``parent`` ``(k,)`` (-1: none); their indices."""
        self._room(len(p))
        k = np.arange(self.count, self.count + len(p), dtype=np.int64)
        self.xy[k] = p
        self.parent[k] = parent
        self.count += len(p)
        return k

    def set_path(self, m: int, path: np.ndarray) -> None:
        """Agent ``m``'s path is now ``path`` (points, from its start; at least one)."""
        self._path_room(len(path))
        self._paths[m, :len(path)] = path
        self.length[m] = len(path)
        self.tip[m] = path[-1]

    def record(self, xy: np.ndarray, who: np.ndarray) -> None:
        """The agents at ``xy`` ``(m, 2)`` now: those of ``who`` (a mask) that have moved ``spacing`` add a point."""
        self._replay(np.ascontiguousarray(xy, dtype=float)[None], np.ascontiguousarray(who, dtype=bool), self.spacing)

    def replay(self, trail: np.ndarray, who: np.ndarray | None = None) -> None:
        """:meth:`record` of the agents ``who`` (a mask; default all) at ``trail[s]`` ``(k, m, 2)``, ``s`` in order.

        A quiet stretch's steps, replayed.
        """
        who = np.ones(trail.shape[1], dtype=bool) if who is None else np.ascontiguousarray(who, dtype=bool)
        self._replay(np.ascontiguousarray(trail, dtype=float), who, self.spacing)

    def _replay(self, trail: np.ndarray, who: np.ndarray, spacing: float) -> None:
        """:func:`record_points` of ``trail`` ``(k, m, 2)`` for the agents ``who``, with room made first."""
        k = len(trail)
        self._room(k * int(np.count_nonzero(who)))
        self._path_room(int(self.length.max(initial=0)) + k)
        self.count = int(record_points(self.xy, self.parent, self.count, self._paths, self.length, self.tip, trail,
                                       who, float(spacing), float(self.erase)))

    def back(self, m: int, p: np.ndarray, reach: float) -> int:
        """The point agent ``m`` at ``p`` backs up to next, the points within ``reach`` forgotten (-1: none left)."""
        path = self._paths[m]
        k = int(self.length[m])
        while k > 1 and np.hypot(*(self.xy[path[k - 1]] - p)) <= reach:
            k -= 1
        self.length[m] = k
        self.tip[m] = path[k - 1]
        return -1 if k == 1 and np.hypot(*(self.xy[path[0]] - p)) <= reach else int(path[k - 1])

    def extend(self, m: int, p: np.ndarray) -> int:
        """Agent ``m``'s path goes on to ``p``, loops erased; the new point."""
        trail = np.zeros((1, len(self.length), 2))
        trail[0, m] = p
        who = np.zeros(len(self.length), dtype=bool)
        who[m] = True
        self._replay(trail, who, 0.0)
        return int(self.tip[m])
