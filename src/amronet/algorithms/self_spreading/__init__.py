"""Self-spreading (the paper's section 4): routers walk out and stop where about to lose their last reference.

The controller (:mod:`.controller`, the readable reference), its walk rules (:mod:`.walks`), its fast step
(:mod:`.fast`) and kernels (:mod:`.kernels`).
"""

from amronet.algorithms.self_spreading.controller import SelfSpreading, SelfSpreadingParams

__all__ = ["SelfSpreading", "SelfSpreadingParams"]
