"""The short runs that compile the potential field's kernels ahead of a first run (:mod:`amronet.sim.warmup`)."""

from __future__ import annotations

from amronet.algorithms.base import WarmUp

__all__ = ["PRESET", "warm_ups"]

PRESET = "potential-field-obstacles-6x6"
"""The preset the potential field is warmed up on."""


def warm_ups() -> list[WarmUp]:
    """Its defaults and a batch (the figures' runs)."""
    return [WarmUp("algorithm potential-field", PRESET),
            WarmUp("batch potential field", "potential-field-6x6", seeds=(1, 2))]
