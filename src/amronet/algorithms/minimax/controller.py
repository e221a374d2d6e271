"""Minimax, Wang, Cao and La Porta's Voronoi-based deployment (IEEE INFOCOM 2004; IEEE TMC 5(6), 2006), a baseline.

The cell and the coverage hole are VOR's (:mod:`amronet.algorithms.common.cells`; *location-aware*): a hole is a
cell vertex farther than the sensing radius ``r_s``. Instead of chasing the farthest vertex, which may turn a near
vertex into the next farthest, Minimax moves the robot to the cell's *minimax point*, the point whose farthest
vertex is nearest: the centre of the smallest circle enclosing the cell's vertices (compiled, Welzl's incremental
algorithm: :mod:`.kernels`), which lies in the (convex) cell. The move is cut to ``max_move_factor r_c``
(Wang et al.: ``r_c / 2``); Wang et al.'s movement adjustment (the move must cover more of the present cell, by
``min_gain`` of the sensing disk's area) and oscillation control (no move straight back: wait a round) apply.

Stop rule: a robot with no hole, within ``tolerance_factor r_c`` of its minimax point, or whose move would not
gain, stays (state *reference*); the run has converged when no robot has a move at the start of a round.
"""

from __future__ import annotations

import numpy as np

from amronet.algorithms.base import ALGORITHMS
from amronet.algorithms.common.cell_rounds import HoleRounds
from amronet.algorithms.common.cells import farthest_point, gains
from amronet.algorithms.common.polygons import Polygons
from amronet.algorithms.minimax.kernels import enclosing_centres
from amronet.algorithms.minimax.params import MinimaxParams

__all__ = ["Minimax", "MinimaxParams", "minimax_points"]


def minimax_points(cells: Polygons) -> np.ndarray:
    """The centre ``(M, 2)`` of the smallest circle enclosing each cell's vertices, relative to the robot.

    A cell of fewer than 3 vertices: ``0``.
    """
    return enclosing_centres(cells)


@ALGORITHMS.register("minimax")
class Minimax(HoleRounds):
    """Controller of Minimax routers."""

    Params = MinimaxParams
    params: MinimaxParams

    def goals(self, robots: np.ndarray, cells: Polygons) -> tuple[np.ndarray, np.ndarray]:  # noqa: D102
        p = self.params
        far, _ = farthest_point(cells, self.reach)
        move = minimax_points(cells)
        length = np.hypot(move[:, 0], move[:, 1])
        move *= np.minimum(1.0, self.max_move / np.maximum(length, 1e-300))[:, None]
        candidates = (far > self.r_s * (1.0 + 1e-9)) & (length > p.tolerance_factor * self.r_c)
        return move, gains(cells, move, candidates, self.r_s, p.disk_vertices, p.min_gain)
