"""VOR's parameters (:class:`VORParams`): light, no kernels (a scenario is checked before a run is set up)."""

from __future__ import annotations

from amronet.algorithms.common.cell_params import HoleParams

__all__ = ["VORParams"]


class VORParams(HoleParams):
    """Parameters of VOR (Wang, Cao and La Porta; what their papers leave open is our documented choice).

    Attributes:
        sensing_radius_factor: Sensing radius ``r_s`` as a fraction of ``r_c`` (the paper's virtual sensing radius,
            6.2: 0.5; then ``r_c = 2 r_s``).
        min_gain: A robot moves only if its move covers more of its cell, by at least this fraction of the sensing
            disk's area (Wang et al.'s movement adjustment; the value is our choice).
        oscillation_control: A robot whose move would point back against its last round's move waits a round
            (Wang et al.).
        cell_radius_factor: The cell's bounding disk as a fraction of ``r_c``; ``None`` (the default): no disk, the
            cell reaches to the area's bounding box where no heard node or seen wall bounds it, as Wang et al.'s
            cells do.
        max_move_factor: The longest move of a round as a fraction of ``r_c`` (Wang et al.: half the communication
            range).
        round_s: Seconds per round (default: the time the longest move takes at full speed).
        disk_vertices: Vertices of the polygons standing for the bounding and the sensing disks.
        memory_points: Obstacle points each robot remembers (the most recent; our choice).
        memory_cell_m: Obstacle points within one grid cell of this size (metres) are remembered once (our choice).
    """
