"""VOR, Wang, Cao and La Porta's Voronoi-based deployment (IEEE INFOCOM 2004; IEEE TMC 5(6), 2006), as a baseline.

A robot's cell is its local Voronoi cell (:mod:`amronet.algorithms.common.cells`): bounded by the communication
range, cut by the bisectors of the nodes it hears (where they announce they are: VOR is *location-aware*, unlike
the paper's rules), by the walls its own sensors have seen and by the area's bounding box. Its sensing disk (radius
``r_s``) leaves a *coverage hole* when the cell's farthest vertex ``v`` is farther than ``r_s``. Then, each round
(:mod:`amronet.algorithms.common.cell_rounds`), VOR pulls the robot towards ``v``::

    move = (|v - p| - r_s) (v - p) / |v - p|,   |move| <= max_move_factor r_c  (Wang et al.: r_c / 2)

so that ``v`` would just be covered. Wang et al.'s two safeguards: *movement adjustment*, the robot moves only if
the move covers more of its (current) cell, here by at least ``min_gain`` of the sensing disk's area; *oscillation
control*, a move that points back against the last round's move waits a round instead. When several vertices are
farthest (an arc of the bounding disk), the middle of the arc stands for them.

Stop rule: a robot with no hole, or whose move would not gain, stays (state *reference*); the run has converged
when no robot has a move at the start of a round (Wang et al.'s rounds end when no sensor moves).
"""

from __future__ import annotations

import numpy as np

from amronet.algorithms.base import ALGORITHMS
from amronet.algorithms.common.cell_rounds import HoleRounds
from amronet.algorithms.common.cells import farthest_point, gains
from amronet.algorithms.common.polygons import Polygons
from amronet.algorithms.vor.params import VORParams

__all__ = ["VOR", "VORParams"]


@ALGORITHMS.register("vor")
class VOR(HoleRounds):
    """Controller of VOR routers."""

    Params = VORParams
    params: VORParams

    def goals(self, robots: np.ndarray, cells: Polygons) -> tuple[np.ndarray, np.ndarray]:  # noqa: D102
        far, vertex = farthest_point(cells, self.reach)
        hole = far > self.r_s * (1.0 + 1e-9)
        move = vertex * (np.maximum(far - self.r_s, 0.0) / np.maximum(far, 1e-300))[:, None]
        length = np.hypot(move[:, 0], move[:, 1])
        move *= np.minimum(1.0, self.max_move / np.maximum(length, 1e-300))[:, None]
        p = self.params
        return move, gains(cells, move, hole, self.r_s, p.disk_vertices, p.min_gain)

