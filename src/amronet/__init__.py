"""amronet: build and evaluate Ad-hoc Mobile Router Networks (AMRoNet).

Example:
    >>> import amronet
    >>> result = amronet.run("self-spreading-6x6", seed=3, overrides={"sim.time_limit": 5})
    >>> 0.0 <= result.summary["coverage"] <= 1.0
    True

The names below are loaded on first use (``amronet.run``, ``from amronet import Simulation``): ``import amronet``
itself imports neither numba nor scipy, so the command line answers ``--help`` or refuses a bad option at once.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

from amronet.errors import AmronetError, MapError, ScenarioError
from amronet.numba_setup import install as _install_numba_setup
from amronet.version import __version__

if TYPE_CHECKING:
    from amronet.scenario import Scenario, list_presets, load_scenario
    from amronet.sim import Simulation
    from amronet.sim.api import run

_install_numba_setup()  # the kernel cache and the thread pool, once numba is imported (see amronet.numba_setup)

_LAZY = {"Scenario": "amronet.scenario", "list_presets": "amronet.scenario", "load_scenario": "amronet.scenario",
         "Simulation": "amronet.sim", "run": "amronet.sim.api"}
"""The public names loaded on first use, and the module that defines each."""

__all__ = [
    "AmronetError",
    "MapError",
    "Scenario",
    "ScenarioError",
    "Simulation",
    "__version__",
    "list_presets",
    "load_scenario",
    "run",
]


def __getattr__(name: str) -> Any:
    if name not in _LAZY:
        raise AttributeError(f"module 'amronet' has no attribute {name!r}")
    value = getattr(importlib.import_module(_LAZY[name]), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted({*globals(), *_LAZY})
