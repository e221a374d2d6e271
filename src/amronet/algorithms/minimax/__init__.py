"""Minimax, Wang, Cao and La Porta's Voronoi-based deployment (a location-aware baseline).

Its parameters (:mod:`.params`) and controller (:mod:`.controller`). Importing the package only declares the
algorithm (:mod:`amronet.algorithms.declaration`, no kernels).
"""

from amronet.algorithms.declaration import declare
from amronet.algorithms.minimax.params import MinimaxParams

__all__ = ["MinimaxParams"]

declare("minimax", controller="amronet.algorithms.minimax.controller", params=MinimaxParams)
