"""Self-spreading (the paper's section 4): routers walk out and stop where about to lose their last reference.

The controller (:mod:`.controller`, the readable reference), its walk rules (:mod:`.walks`), its fast step
(:mod:`.fast`) and kernels (:mod:`.kernels`, :mod:`.step_passes`); its parameters: :mod:`.params`. Importing the
package only declares the algorithm (:mod:`amronet.algorithms.declaration`, no kernels).
"""

from amronet.algorithms.declaration import declare
from amronet.algorithms.self_spreading.params import SelfSpreadingParams

__all__ = ["SelfSpreadingParams"]

declare("self-spreading", controller="amronet.algorithms.self_spreading.controller", params=SelfSpreadingParams)
