"""The short runs that compile agent-assisted deployment's kernels ahead of a first run (:mod:`amronet.sim.warmup`)."""

from __future__ import annotations

from amronet.algorithms.agent_assisted.drops.base import DROP_RULES
from amronet.algorithms.agent_assisted.explorers.base import EXPLORERS
from amronet.algorithms.base import WarmUp
from amronet.engine.radio import MEDIA

__all__ = ["PRESET", "warm_ups"]

PRESET = "agent-assisted-office"
"""The preset agent-assisted deployment is warmed up on."""


def warm_ups() -> list[WarmUp]:
    """Its defaults, every explorer, drop rule and radio model (with the frontier explorer), faults and repair.

    The frontier explorer's case starts first (the longest chain of kernels); the figures replace it with their own
    agents (:mod:`amronet.sim.warmup`).
    """
    frontier = {"algorithm.params.explorer": "frontier"}
    return [
        WarmUp("algorithm agent-assisted", PRESET),
        *(WarmUp(f"explorer {name}", PRESET, {"algorithm.params.explorer": name}, first=name == "frontier")
          for name in EXPLORERS),
        *(WarmUp(f"drop rule {name}", PRESET, {"algorithm.params.drop_rule": name, **frontier}) for name in DROP_RULES),
        *(WarmUp(f"radio {name}, agents", PRESET, {"radio.model": name, **frontier}) for name in MEDIA),
        WarmUp("faults and relocation", PRESET,
               {"faults": [{"at": 1.0, "routers": 0.5}], "algorithm.params.repair": "relocate", **frontier,
                "sim.coverage_target": "off"}),
    ]
