"""Lloyd's parameters (:class:`LloydParams`): light, no kernels (a scenario is checked before a run is set up)."""

from __future__ import annotations

from typing import Annotated

from pydantic import Field

from amronet.algorithms.common.cell_params import CellParams

__all__ = ["LloydParams"]


class LloydParams(CellParams):
    """Parameters of Lloyd's algorithm towards a centroidal Voronoi tessellation (Cortés et al.).

    Attributes:
        cell_radius_factor: The cell's bounding disk as a fraction of ``r_c`` (Cortés, Martínez and Bullo's
            limited-range cells: half the communication range, 0.5, within which the cell is exact).
        tolerance_factor: A robot within this fraction of ``r_c`` of its cell's centroid stays (our choice).
        max_move_factor: The longest move of a round as a fraction of ``r_c`` (a centroid is never farther than
            ``cell_radius_factor r_c``).
        round_s: Seconds per round, one Lloyd step (default: the time the longest move takes at full speed).
        disk_vertices: Vertices of the polygon standing for the bounding disk.
        memory_points: Obstacle points each robot remembers (the most recent; our choice).
        memory_cell_m: Obstacle points within one grid cell of this size (metres) are remembered once (our choice).
    """

    cell_radius_factor: Annotated[float, Field(strict=True, gt=0, le=1, allow_inf_nan=False)] = 0.5
    tolerance_factor: Annotated[float, Field(strict=True, gt=0, lt=1, allow_inf_nan=False)] = 0.01
