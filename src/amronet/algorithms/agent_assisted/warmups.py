"""The short runs that compile agent-assisted deployment's kernels ahead of a first run (:mod:`amronet.sim.warmup`)."""

from __future__ import annotations

from collections.abc import Mapping

from amronet.algorithms.agent_assisted.drops.base import DROP_RULES
from amronet.algorithms.agent_assisted.explorers.base import EXPLORERS
from amronet.algorithms.base import WarmUp
from amronet.engine.radio import MEDIA

__all__ = ["PRESET", "driven_inside", "warm_ups"]

PRESET = "agent-assisted-office"
"""The preset agent-assisted deployment is warmed up on."""


def driven_inside(registry: Mapping[str, type]) -> list[str]:
    """The names of a registry whose members run on their own: not those an environment drives (``external``).

    An ``external`` explorer or drop rule takes its commands from :mod:`amronet.env`; the kernels of its runs are the
    phases' own, which the other runs compile.
    """
    return [name for name, cls in registry.items() if not getattr(cls, "external", False)]


def warm_ups() -> list[WarmUp]:
    """Its defaults, every explorer, drop rule, radio model (frontier explorer), switch, faults and repairs.

    The agents' switches and triangle routers driving in the compiled step have a case each.

    The frontier explorer's case starts first (the longest chain of kernels); the figures replace it with their own
    agents (:mod:`amronet.sim.warmup`).
    """
    frontier = {"algorithm.params.explorer": "frontier"}
    return [
        WarmUp("algorithm agent-assisted", PRESET),
        *(WarmUp(f"explorer {name}", PRESET, {"algorithm.params.explorer": name}, first=name == "frontier")
          for name in driven_inside(EXPLORERS)),
        *(WarmUp(f"drop rule {name}", PRESET, {"algorithm.params.drop_rule": name, **frontier})
          for name in driven_inside(DROP_RULES)),
        *(WarmUp(f"radio {name}, agents", PRESET, {"radio.model": name, **frontier}) for name in MEDIA),
        WarmUp("agents' switches", PRESET,  # the compiled step under drop_settle_s, reverse_drop, when_empty
               {"agents.when_empty": "continue", "agents.routers_carried": 2, "agents.drop_settle_s": 0.5,
                "agents.reverse_drop": 1.0, "algorithm.params.drop_rule": "distance-junction", **frontier}),
        WarmUp("triangles in the compiled step", "agent-assisted-office-4bs",  # (steps a stretch does not take)
               {"agents.per_base": 1, "radio.model": "multi-wall", **frontier}, seconds=40.0),
        WarmUp("faults and relocation", PRESET,  # (late enough that routers relocate in a stretch)
               {"faults": [{"at": 45.0, "routers": 0.5}], "algorithm.params.repair": "relocate", **frontier,
                "sim.coverage_target": "off"}, seconds=90.0),
        WarmUp("faults and retrace", PRESET,  # (the breadcrumbs' kernel)
               {"faults": [{"at": 1.0, "routers": 0.5}], "algorithm.params.repair": "retrace", **frontier,
                "sim.coverage_target": "off"}),
    ]
