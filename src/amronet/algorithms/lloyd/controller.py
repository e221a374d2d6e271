"""Lloyd's algorithm towards a centroidal Voronoi tessellation, a baseline.

As Cortés, Martínez, Karataş and Bullo run it on robots (*Coverage control for mobile sensing networks*, IEEE
T-RA 20(2), 2004): each round (:mod:`amronet.algorithms.common.cell_rounds`) every robot moves to the
centroid of its cell, weighted by a uniform density on the free space it knows::

    C_i = (1 / |W_i|) ∫_{W_i} x dx,     W_i = V_i ∩ B(p_i, R) ∩ F_i

with ``V_i`` the Voronoi cell of the nodes it hears (where they announce they are: Lloyd is *location-aware*, unlike
the paper's rules), ``B(p_i, R)`` the disk of radius ``R = cell_radius_factor r_c`` (Cortés, Martínez and Bullo's
limited-range cells, *ESAIM: COCV* 11, 2005: ``R = r_c / 2``, within which the cell built from what a robot hears
is exact) and ``F_i`` the free space it has seen (the area's bounding box, less what lies beyond the obstacle
points its sensors hit: :mod:`amronet.algorithms.common.cells`). A robot at the centroid of its cell no longer
lowers the coverage cost ``H = sum_i ∫_{W_i} |x - p_i|^2 dx``; every move towards the centroid lowers it (Cortés et
al.), so Lloyd needs neither oscillation control nor a coverage test.

Stop rule: a robot within ``tolerance_factor r_c`` of its centroid stays (state *reference*); the run has
converged when no robot has a move at the start of a round (a centroidal configuration, to that tolerance).
"""

from __future__ import annotations

import numpy as np

from amronet.algorithms.base import ALGORITHMS
from amronet.algorithms.common.cell_rounds import CellRounds
from amronet.algorithms.common.polygons import Polygons, area_centroid
from amronet.algorithms.lloyd.params import LloydParams

__all__ = ["Lloyd", "LloydParams"]


@ALGORITHMS.register("lloyd")
class Lloyd(CellRounds):
    """Controller of Lloyd routers."""

    Params = LloydParams
    params: LloydParams

    def goals(self, robots: np.ndarray, cells: Polygons) -> tuple[np.ndarray, np.ndarray]:  # noqa: D102
        area, centroid = area_centroid(cells)
        length = np.hypot(centroid[:, 0], centroid[:, 1])
        return centroid, (area > 0.0) & (length > self.params.tolerance_factor * self.r_c)
