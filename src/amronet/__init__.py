"""amronet: build and evaluate Ad-hoc Mobile Router Networks (AMRoNet).

Example:
    >>> import amronet
    >>> result = amronet.run("self-spreading-6x6", seed=3, overrides={"sim.time_limit": 5})
    >>> 0.0 <= result.summary["coverage"] <= 1.0
    True
"""

from amronet.kernel_cache import configure as _configure_kernel_cache
from amronet.threads import configure as _configure_threads
from amronet.version import __version__

_configure_kernel_cache()  # before any module with kernels is imported (see amronet.kernel_cache)
_configure_threads()  # a fork-safe thread pool for the few threaded kernels (see amronet.threads)

from amronet.errors import AmronetError, MapError, ScenarioError  # noqa: E402
from amronet.scenario import Scenario, list_presets, load_scenario  # noqa: E402
from amronet.sim import Simulation  # noqa: E402
from amronet.sim.api import run  # noqa: E402

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
