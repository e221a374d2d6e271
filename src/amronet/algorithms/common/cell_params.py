"""The parameters the Voronoi-cell baselines share (VOR, Minimax, Lloyd): light, no kernels.

Every value is a fraction of the communication radius ``r_c`` unless its name says otherwise; where it comes from
is said in ``docs/baselines.md`` and in each algorithm's controller docstring.
"""

from __future__ import annotations

from typing import Annotated

from pydantic import BaseModel, ConfigDict, Field, StrictInt

from amronet.yaml_fields import YamlBool

__all__ = ["CellParams", "HoleParams"]

_Fraction = Annotated[float, Field(strict=True, gt=0, le=1, allow_inf_nan=False)]


class CellParams(BaseModel):
    """What the Voronoi-cell baselines share.

    Attributes:
        cell_radius_factor: The cell is bounded by the disk of this radius about the robot, as a fraction of
            ``r_c`` (beyond what it hears a robot knows of no other node).
        max_move_factor: The longest move of one round, as a fraction of ``r_c`` (Wang et al.: half the
            communication range, because a cell built from what one robot hears may be too large).
        round_s: Seconds per round (every robot decides at the start of a round, then drives towards its goal);
            default: the time a router takes to drive the longest move at full speed.
        disk_vertices: Vertices of the polygon that stands for the bounding disk (and, for VOR and Minimax, for
            the sensing disk in the coverage test): 32 keeps its area within 0.7 % of the disk's.
        memory_points: Obstacle points each robot remembers (the most recent ones; our choice).
        memory_cell_m: Obstacle points closer than this (metres, on a grid) are remembered once (our choice).
    """

    model_config = ConfigDict(extra="forbid", frozen=True)

    cell_radius_factor: _Fraction = 1.0
    max_move_factor: _Fraction = 0.5
    round_s: Annotated[float, Field(strict=True, gt=0, le=1e6, allow_inf_nan=False)] | None = None
    disk_vertices: Annotated[StrictInt, Field(ge=8, le=256)] = 32
    memory_points: Annotated[StrictInt, Field(ge=0, le=1024)] = 64
    memory_cell_m: Annotated[float, Field(strict=True, gt=0, le=10, allow_inf_nan=False)] = 0.05


class HoleParams(CellParams):
    """What Wang, Cao and La Porta's VOR and Minimax share besides the cell: the sensing disk and its coverage holes.

    Their parameters (:class:`~amronet.algorithms.vor.params.VORParams`,
    :class:`~amronet.algorithms.minimax.params.MinimaxParams`) take these descriptions (the scenario reference reads
    a field's description from the nearest class that has one).

    Attributes:
        cell_radius_factor: The cell's bounding disk as a fraction of ``r_c``; ``None`` (the default): no disk, the
            cell reaches to the area's bounding box where no heard node or seen wall bounds it, as Wang et al.'s
            cells do.
        max_move_factor: The longest move of a round as a fraction of ``r_c`` (Wang et al.: half the communication
            range).
        round_s: Seconds per round (default: the time the longest move takes at full speed).
        disk_vertices: Vertices of the polygons standing for the bounding and the sensing disks.
        memory_points: Obstacle points each robot remembers (the most recent; our choice).
        memory_cell_m: Obstacle points within one grid cell of this size (metres) are remembered once (our choice).
        sensing_radius_factor: Sensing radius ``r_s`` as a fraction of ``r_c`` (the paper's virtual sensing radius,
            6.2: 0.5; then ``r_c = 2 r_s``).
        min_gain: A robot moves only if its move covers more of its cell, by at least this fraction of the sensing
            disk's area (Wang et al.'s movement adjustment; the value is our choice).
        oscillation_control: A robot whose move would point back against its last round's move waits a round
            (Wang et al.).
    """

    sensing_radius_factor: _Fraction = 0.5  # r_c = 2 r_s: a field the sensing disks cover is a connected network
    cell_radius_factor: _Fraction | None = None  # a disk's arc is no Voronoi edge: with one, Minimax would take a
    # robot on the edge of the swarm to be at its minimax point
    min_gain: Annotated[float, Field(strict=True, ge=0, lt=1, allow_inf_nan=False)] = 0.01
    oscillation_control: YamlBool = True
