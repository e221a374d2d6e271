"""The building blocks of the scenario's schema: its number types and the strict base of every section."""

from __future__ import annotations

from typing import Annotated

from pydantic import BaseModel, ConfigDict, Field, StrictInt

from amronet.limits import MAX_COUNT

__all__ = ["MAX_RANGE_M", "Count", "FiniteFloat", "NodeId", "NonNegativeFloat", "PositiveFloat", "Strict"]

PositiveFloat = Annotated[float, Field(strict=True, gt=0, allow_inf_nan=False)]
NonNegativeFloat = Annotated[float, Field(strict=True, ge=0, allow_inf_nan=False)]
FiniteFloat = Annotated[float, Field(strict=True, allow_inf_nan=False)]
Count = Annotated[StrictInt, Field(ge=0, le=MAX_COUNT)]
"""A number of robots (at most :data:`~amronet.limits.MAX_COUNT`: larger ones are typos)."""
NodeId = Annotated[StrictInt, Field(ge=0, lt=MAX_COUNT)]

MAX_RANGE_M = 1e5
"""The longest median range ``radio.r_c`` (100 km): longer ones overflow the controllers' squared ranges and the
pictures' arithmetic, and no floor plan needs them."""


class Strict(BaseModel):
    """A section of a scenario: unknown keys are errors, and a validated section does not change."""

    model_config = ConfigDict(extra="forbid", frozen=True)
