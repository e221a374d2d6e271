"""The potential-field baseline (Howard et al.; Poduri and Sukhatme).

The controller (:mod:`.controller`), its fast step (:mod:`.fast`) and kernels (:mod:`.kernels`).
"""

from amronet.algorithms.potential_field.controller import PotentialField, PotentialFieldParams

__all__ = ["PotentialField", "PotentialFieldParams"]
