"""VOR, Wang, Cao and La Porta's Voronoi-based deployment (a location-aware baseline).

Its parameters (:mod:`.params`) and controller (:mod:`.controller`). Importing the package only declares the
algorithm (:mod:`amronet.algorithms.declaration`, no kernels).
"""

from amronet.algorithms.declaration import declare
from amronet.algorithms.vor.params import VORParams

__all__ = ["VORParams"]

declare("vor", controller="amronet.algorithms.vor.controller", params=VORParams)
