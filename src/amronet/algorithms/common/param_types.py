"""Types that several algorithms' parameter models share; light (no NumPy, no kernels), like the models themselves."""

from __future__ import annotations

from typing import Literal

__all__ = ["TriangularMode"]

TriangularMode = Literal["off", "none", "global", "local"]
"""Triangular deployment's rule (:mod:`amronet.algorithms.common.triangular`): ``off``, ``none``, ``global`` or
``local``."""
