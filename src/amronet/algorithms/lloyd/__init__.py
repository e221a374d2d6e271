"""Lloyd's algorithm towards a centroidal Voronoi tessellation (Cortés et al.; a location-aware baseline).

Its parameters (:mod:`.params`) and controller (:mod:`.controller`). Importing the package only declares the
algorithm (:mod:`amronet.algorithms.declaration`, no kernels).
"""

from amronet.algorithms.declaration import declare
from amronet.algorithms.lloyd.params import LloydParams

__all__ = ["LloydParams"]

declare("lloyd", controller="amronet.algorithms.lloyd.controller", params=LloydParams)
