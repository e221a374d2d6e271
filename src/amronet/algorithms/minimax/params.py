"""Minimax's parameters (:class:`MinimaxParams`): light, no kernels (a scenario is checked before a run is set up)."""

from __future__ import annotations

from typing import Annotated

from pydantic import Field

from amronet.algorithms.common.cell_params import HoleParams

__all__ = ["MinimaxParams"]


class MinimaxParams(HoleParams):
    """Parameters of Minimax (Wang, Cao and La Porta; what their papers leave open is our documented choice).

    Attributes:
        tolerance_factor: A robot within this fraction of ``r_c`` of its minimax point stays (our choice).

    The other fields and their descriptions are :class:`~amronet.algorithms.common.cell_params.HoleParams`'.
    """

    tolerance_factor: Annotated[float, Field(strict=True, gt=0, lt=1, allow_inf_nan=False)] = 0.01
