"""The potential field's parameters (:class:`PotentialFieldParams`): light, no kernels (a scenario is checked first)."""

from __future__ import annotations

from typing import Annotated

from pydantic import BaseModel, ConfigDict, Field, StrictInt

from amronet.limits import MAX_COUNT
from amronet.yaml_fields import YamlBool

__all__ = ["PotentialFieldParams"]

_Positive = Annotated[float, Field(strict=True, gt=0, allow_inf_nan=False)]


class PotentialFieldParams(BaseModel):
    """Parameters of the potential-field algorithm.

    Attributes:
        connectivity_k: ``K`` of K-connectivity; 0 is Howard et al.'s plain potential field.
        damping: Viscous friction coefficient ``nu`` (Poduri & Sukhatme: 0.25).
        safety_factor: ``Q`` (Poduri & Sukhatme: 0.8).
        mass: Virtual mass ``m`` (our choice: 1).
        sensing_radius_factor: Virtual sensing radius ``r_s`` as a fraction of ``r_c`` (paper 6.2: 0.5).
        balance_fraction: Where cover and degree forces balance, as a fraction of ``Q r_c`` (our choice: 0.75).
        k_cover: Override the derived ``K_cover``.
        k_degree: Override the derived ``K_degree``.
        obstacle_forces: Add forces from obstacle points seen by the range sensors.
        k_obstacle: Override ``K_obstacle`` (default ``K_cover``).
        rest_fraction: Mean speed over a window below which a router counts as at rest, as a fraction of its
            maximum speed (our choice: 0.05). A router rests only under a force that would drive it at no more
            than twice that speed (or when a wall holds it), and wakes up when the force changes by as much.
        rest_steps: Length of that window in steps (our choice: 20).
        force_cap_factor: Cap of a single force, in units of ``nu v_max`` (the force that holds full speed).
    """

    model_config = ConfigDict(extra="forbid", frozen=True)

    connectivity_k: Annotated[StrictInt, Field(ge=0, le=MAX_COUNT)] = 1
    damping: _Positive = 0.25
    safety_factor: Annotated[float, Field(strict=True, gt=0, le=1, allow_inf_nan=False)] = 0.8
    mass: _Positive = 1.0
    sensing_radius_factor: Annotated[float, Field(strict=True, gt=0, le=1, allow_inf_nan=False)] = 0.5
    balance_fraction: Annotated[float, Field(strict=True, gt=0, lt=1, allow_inf_nan=False)] = 0.75
    k_cover: _Positive | None = None
    k_degree: _Positive | None = None
    obstacle_forces: YamlBool = True
    k_obstacle: _Positive | None = None
    rest_fraction: Annotated[float, Field(strict=True, gt=0, lt=1, allow_inf_nan=False)] = 0.05
    rest_steps: Annotated[StrictInt, Field(ge=1, le=MAX_COUNT)] = 20
    force_cap_factor: Annotated[float, Field(strict=True, gt=0, allow_inf_nan=False)] = 4.0
