"""The short run that compiles DSSA's kernels ahead of a first run (:mod:`amronet.sim.warmup`)."""

from __future__ import annotations

from amronet.algorithms.base import WarmUp

__all__ = ["PRESET", "warm_ups"]

PRESET = "dssa-obstacles-6x6"
"""The preset DSSA is warmed up on."""


def warm_ups() -> list[WarmUp]:
    """Its defaults."""
    return [WarmUp("algorithm dssa", PRESET)]
