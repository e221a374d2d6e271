"""VOR's parameters (:class:`VORParams`): light, no kernels (a scenario is checked before a run is set up)."""

from __future__ import annotations

from amronet.algorithms.common.cell_params import HoleParams

__all__ = ["VORParams"]


class VORParams(HoleParams):
    """Parameters of VOR (Wang, Cao and La Porta; what their papers leave open is our documented choice).

    Its fields and their descriptions are :class:`~amronet.algorithms.common.cell_params.HoleParams`'.
    """
