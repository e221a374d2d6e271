"""Self-spreading's parameters (:class:`SelfSpreadingParams`): light, no kernels (a scenario is checked first)."""

from __future__ import annotations

from typing import Annotated, Literal

from pydantic import BaseModel, ConfigDict, Field, StrictInt, model_validator

from amronet.algorithms.common.param_types import TriangularMode
from amronet.limits import MAX_COUNT

__all__ = ["SelfSpreadingParams"]

Decibels = Annotated[float, Field(strict=True, ge=0, le=60, allow_inf_nan=False)]


class SelfSpreadingParams(BaseModel):
    """Parameters of self-spreading.

    Attributes:
        triangular: Triangular deployment: ``off`` (greedy only, an ablation), ``none`` (triangular deployment
            without optimization), ``global`` or ``local`` (the optimizations of paper 4.3).
        loss_margin: Width of the "about to lose" band as a fraction of ``r_c`` (``distance`` stop rule, geometric
            triangles).
        turn_noise: Heading noise of the random walk, radians per square-root second.
        give_up_steps: Consecutive blocked steps after which a triangle router stops short of its goal.
        stop_rule: When an exploring router stops: ``distance`` (the paper's), ``link-quality`` (location-free;
            see the module docstring) or ``external`` (a policy's wish, :mod:`.external`: :mod:`amronet.env`).
        stop_margin_db: ``link-quality``: stop when the smoothed best margin to a reference is below this (dB over
            the usable threshold); also the margin a ``link-quality`` triangle router seeks on both links.
        loss_margin_db: ``link-quality``: stop at once when the raw best margin is below this (dB); below
            ``stop_margin_db``.
        smoothing_s: ``link-quality``: time constant of the margin's moving average, seconds (0: no smoothing).
        triangle_rule: How a triangle router moves: ``geometric`` (to the paper's goal point) or ``link-quality``
            (run-and-tumble on its two link margins; see the module docstring).
        triangle_tolerance_db: ``link-quality`` triangles: settle when both margins are within this of
            ``stop_margin_db`` (dB).
        triangle_max_s: ``link-quality`` triangles: settle after searching this long, seconds.
        walk: How exploring routers walk (:mod:`amronet.algorithms.self_spreading.walks`): ``random`` (the paper's),
        ``straight``,
            ``growth``, ``guided`` or ``external`` (commanded by a policy, :mod:`.external`: :mod:`amronet.env`).
        growth_s: ``growth`` and ``guided`` walks: how long a deployed node counts as new (where the network
            grows), seconds.
        follow_steps: ``growth`` and ``guided`` walks: at most this many steps following an obstacle's edge.
    """

    model_config = ConfigDict(extra="forbid", frozen=True)

    triangular: TriangularMode = "local"
    loss_margin: Annotated[float, Field(strict=True, gt=0, lt=0.5, allow_inf_nan=False)] = 0.05
    turn_noise: Annotated[float, Field(strict=True, ge=0, allow_inf_nan=False)] = 1.0
    give_up_steps: Annotated[StrictInt, Field(ge=1, le=MAX_COUNT)] = 20
    stop_rule: Literal["distance", "link-quality", "external"] = "distance"
    stop_margin_db: Decibels = 3.0
    loss_margin_db: Decibels = 1.0
    smoothing_s: Annotated[float, Field(strict=True, ge=0, le=60, allow_inf_nan=False)] = 0.5
    triangle_rule: Literal["geometric", "link-quality"] = "geometric"
    triangle_tolerance_db: Annotated[float, Field(strict=True, gt=0, le=60, allow_inf_nan=False)] = 1.0
    triangle_max_s: Annotated[float, Field(strict=True, gt=0, allow_inf_nan=False)] = 60.0
    walk: Literal["random", "straight", "growth", "guided", "external"] = "random"
    growth_s: Annotated[float, Field(strict=True, gt=0, le=3600, allow_inf_nan=False)] = 10.0
    follow_steps: Annotated[StrictInt, Field(ge=1, le=100_000)] = 200

    @model_validator(mode="after")
    def _hysteresis(self) -> SelfSpreadingParams:
        if self.stop_margin_db <= self.loss_margin_db:
            raise ValueError(f"@algorithm.params.stop_margin_db@{self.stop_margin_db:g} dB must be above "
                             f"loss_margin_db ({self.loss_margin_db:g} dB): routers stop above the loss threshold")
        return self
