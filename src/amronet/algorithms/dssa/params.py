"""DSSA's parameters (:class:`DSSAParams`): light, no kernels (a scenario is checked before a run is set up)."""

from __future__ import annotations

from typing import Annotated

from pydantic import BaseModel, ConfigDict, Field, StrictInt

from amronet.limits import MAX_COUNT
from amronet.yaml_fields import YamlBool

__all__ = ["DSSAParams"]

_Positive = Annotated[float, Field(strict=True, gt=0, allow_inf_nan=False)]


class DSSAParams(BaseModel):
    """Parameters of DSSA (the published law has none; every default here is our documented choice).

    Attributes:
        sensing_radius_factor: Virtual sensing radius ``r_s`` as a fraction of ``r_c`` (paper 6.2: 0.5).
        field_area: Area ``A`` of the field in m² for the expected density (default: the map's free area).
        obstacle_forces: Add forces from obstacle points seen by the range sensors (paper's experiment 2).
        obstacle_gain: Weight of an obstacle point relative to a neighbour.
        oscillation_limit: Direction reversals within ``oscillation_radius`` after which a router stops.
        oscillation_radius: Radius of the oscillation region as a fraction of ``r_c``.
        stable_fraction: A step shorter than this fraction of the maximum step counts as standing still.
        stable_steps: Steps of standing still in a row after which a router stops.
    """

    model_config = ConfigDict(extra="forbid", frozen=True)

    sensing_radius_factor: Annotated[float, Field(strict=True, gt=0, le=1, allow_inf_nan=False)] = 0.5
    field_area: _Positive | None = None
    obstacle_forces: YamlBool = True
    obstacle_gain: Annotated[float, Field(strict=True, ge=0, allow_inf_nan=False)] = 1.0
    oscillation_limit: Annotated[StrictInt, Field(ge=1, le=MAX_COUNT)] = 10
    oscillation_radius: Annotated[float, Field(strict=True, gt=0, lt=1, allow_inf_nan=False)] = 0.05
    stable_fraction: Annotated[float, Field(strict=True, gt=0, lt=1, allow_inf_nan=False)] = 0.1
    stable_steps: Annotated[StrictInt, Field(ge=1, le=MAX_COUNT)] = 20
