"""The agents' own paths, from odometry: what MARBLE's reverse drop backs up along.

Each agent's path is kept as points sampled every ``spacing`` metres of straight-line progress (cold: an append every
few steps per agent). Backing up, an agent heads for the newest point it has not reached yet and forgets the points
it passes, so the path it walks back is its own, corner by corner.
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
        self.points: list[list[np.ndarray]] = [[p.copy()] for p in xy]
        self._last = np.array(xy, dtype=float, copy=True)

    def update(self, xy: np.ndarray, who: np.ndarray) -> None:
        """Sample the agents ``who`` (a mask ``(n,)``) that have moved ``spacing`` from their newest point."""
        moved = who & (np.linalg.norm(xy - self._last, axis=1) >= self.spacing)
        for m in np.flatnonzero(moved):
            pts = self.points[m]
            pts.append(xy[m].copy())
            if len(pts) > self.limit:
                del pts[0]
            self._last[m] = xy[m]

    def back(self, m: int, p: np.ndarray) -> np.ndarray | None:
        """The point agent ``m`` at ``p`` backs up to next, forgetting the points reached (``None``: none left)."""
        pts = self.points[m]
        while pts and np.linalg.norm(pts[-1] - p) < 0.5 * self.spacing:
            pts.pop()
        if not pts:
            return None
        self._last[m] = pts[-1]
        return pts[-1]
