"""The potential-field baseline (Howard et al.; Poduri and Sukhatme).

Its parameters (:mod:`.params`), controller (:mod:`.controller`), fast step (:mod:`.fast`) and kernels
(:mod:`.kernels`). Importing the package only declares the algorithm (:mod:`amronet.algorithms.declaration`, no
kernels).
"""

from amronet.algorithms.declaration import declare
from amronet.algorithms.potential_field.params import PotentialFieldParams

__all__ = ["PotentialFieldParams"]

declare("potential-field", controller="amronet.algorithms.potential_field.controller", params=PotentialFieldParams)
