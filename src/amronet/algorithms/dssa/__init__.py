"""DSSA, the distributed self-spreading algorithm of Heo and Varshney (a baseline).

Its parameters (:mod:`.params`) and controller (:mod:`.controller`). Importing the package only declares the
algorithm (:mod:`amronet.algorithms.declaration`, no kernels).
"""

from amronet.algorithms.declaration import declare
from amronet.algorithms.dssa.params import DSSAParams

__all__ = ["DSSAParams"]

declare("dssa", controller="amronet.algorithms.dssa.controller", params=DSSAParams)
