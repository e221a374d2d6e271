"""DSSA, the distributed self-spreading algorithm of Heo and Varshney (a baseline).

The controller: :mod:`.controller`.
"""

from amronet.algorithms.dssa.controller import DSSA, DSSAParams

__all__ = ["DSSA", "DSSAParams"]
