"""Deployment algorithms, one package each, declared by name in :data:`ALGORITHMS`.

Importing a package only declares its algorithm (:mod:`amronet.algorithms.declaration`: light, no kernels); its
controller is imported on first lookup. The protocol's names (``Controller``, ``Setup``, ...) load on first use.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

from amronet.algorithms import (  # noqa: F401  (declare themselves)
    agent_assisted,
    dssa,
    lloyd,
    minimax,
    potential_field,
    self_spreading,
    vor,
)
from amronet.algorithms.declaration import ALGORITHMS

if TYPE_CHECKING:
    from amronet.algorithms.base import (
        AreaKnowledge,
        Command,
        Controller,
        Readings,
        RouterStock,
        Setup,
        StepInput,
    )

_LAZY = ("AreaKnowledge", "Command", "Controller", "Readings", "RouterStock", "Setup", "StepInput")
"""Names of :mod:`amronet.algorithms.base` loaded on first use (it imports NumPy and numba)."""

__all__ = ["ALGORITHMS", "AreaKnowledge", "Command", "Controller", "Readings", "RouterStock", "Setup", "StepInput"]


def __getattr__(name: str) -> Any:
    if name not in _LAZY:
        raise AttributeError(f"module 'amronet.algorithms' has no attribute {name!r}")
    value = getattr(importlib.import_module("amronet.algorithms.base"), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted({*globals(), *_LAZY})
