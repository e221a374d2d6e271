"""The short run that compiles what Lloyd's first run would otherwise compile (:mod:`amronet.sim.warmup`).

Lloyd has no fast step; the run compiles the kernels of its cells, goals and obstacle memory, and the
loop's sense and move kernels.
"""

from __future__ import annotations

from amronet.algorithms.base import WarmUp

__all__ = ["PRESET", "warm_ups"]

PRESET = "lloyd-obstacles-6x6"
"""The preset Lloyd is warmed up on."""


def warm_ups() -> list[WarmUp]:
    """Its defaults."""
    return [WarmUp("algorithm lloyd", PRESET)]
