"""The agents' own paths, from odometry: what MARBLE's reverse drop backs up along.

Each agent's path is kept as points sampled every ``spacing`` metres of straight-line progress (cold: an append every
few steps per agent). Backing up, an agent heads for the newest point it has not reached yet and forgets the points
it passes, so the path it walks back is its own, corner by corner. The points are kept in arrays (one row of points
per agent, and how many each has), which a quiet stretch reads and updates as these methods do
(:func:`~amronet.algorithms.agent_assisted.stretch_books.back_up`).
"""

from __future__ import annotations

import numpy as np

__all__ = ["Trails"]


class Trails:
    """Sampled paths of ``n`` agents.

    Args:
        xy: The agents' start positions ``(n, 2)``.
        spacing: Distance between samples, metres.
        limit: Most points kept per agent (the oldest go first).
    """

    def __init__(self, xy: np.ndarray, spacing: float, limit: int = 100_000) -> None:
        self.spacing = spacing
        self.limit = limit
        self.points = np.zeros((len(xy), 64, 2))
        """Each agent's points, oldest first ``(n, capacity, 2)``; the first ``count`` of its row are kept."""
        self.points[:, 0] = xy
        self.count = np.ones(len(xy), dtype=np.int64)
        """How many points each agent keeps ``(n,)``."""
        self.last = np.array(xy, dtype=float, copy=True)
        """Each agent's newest point, or the point it last backed up to ``(n, 2)``."""

    def reserve(self, more: int) -> bool:
        """Make room for ``more`` points per agent; ``False`` where an agent could then go beyond ``limit``."""
        need = int(self.count.max(initial=0)) + more
        if need > self.limit:
            return False
        capacity = self.points.shape[1]
        if need > capacity:
            grown = np.zeros((len(self.points), max(need, min(2 * capacity, self.limit)), 2))
            grown[:, :capacity] = self.points
            self.points = grown
        return True

    def update(self, xy: np.ndarray, who: np.ndarray) -> None:
        """Sample the agents ``who`` (a mask ``(n,)``) that have moved ``spacing`` from their newest point."""
        moved = who & (np.linalg.norm(xy - self.last, axis=1) >= self.spacing)
        for m in np.flatnonzero(moved):
            k = int(self.count[m])
            if k == self.limit:  # the oldest goes
                self.points[m, :k - 1] = self.points[m, 1:k].copy()
                k -= 1
            elif k == self.points.shape[1]:
                self.reserve(1)
            self.points[m, k] = xy[m]
            self.count[m] = k + 1
            self.last[m] = xy[m]

    def path(self, m: int) -> np.ndarray:
        """Agent ``m``'s points, oldest first ``(k, 2)`` (a view)."""
        return self.points[m, :self.count[m]]

    def back(self, m: int, p: np.ndarray) -> np.ndarray | None:
        """The point agent ``m`` at ``p`` backs up to next, forgetting the points reached (``None``: none left)."""
        k = int(self.count[m])
        while k and np.linalg.norm(self.points[m, k - 1] - p) < 0.5 * self.spacing:
            k -= 1
        self.count[m] = k
        if not k:
            return None
        self.last[m] = self.points[m, k - 1]
        return self.points[m, k - 1].copy()
