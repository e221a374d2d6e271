"""The short runs that compile self-spreading's kernels ahead of a first run (:mod:`amronet.sim.warmup`)."""

from __future__ import annotations

from amronet.algorithms.base import WarmUp
from amronet.algorithms.self_spreading.walks import WALKS
from amronet.engine.radio import MEDIA

__all__ = ["PRESET", "warm_ups"]

PRESET = "self-spreading-obstacles-6x6"
"""The preset self-spreading is warmed up on."""


def warm_ups() -> list[WarmUp]:
    """Its defaults, every walk rule and radio model, the link-quality rules, triangles, batches, large runs."""
    two_bases = {"base_stations": [{"x": -1.2, "y": 0.0, "region": [0.6, 0.6]},
                                   {"x": 1.2, "y": 0.0, "region": [0.6, 0.6]}]}
    return [
        WarmUp("algorithm self-spreading", PRESET, first=True),  # its stretch: the second-longest chain
        *(WarmUp(f"walk {name}", PRESET, {"algorithm.params.walk": name}) for name in WALKS),
        # (log-distance's hearing kernels, which agent-assisted's log-distance case shares, start early: that case
        # runs after the frontier chain and would otherwise wait for them at the end)
        *(WarmUp(f"radio {name}", PRESET, {"radio.model": name}, first=name == "log-distance") for name in MEDIA),
        WarmUp("packet loss, link-quality stop rule", PRESET,
               {"radio.model": "multi-wall", "radio.packet_loss": True, "radio.shadowing_db": 4.0,
                "algorithm.params.stop_rule": "link-quality", "algorithm.params.triangle_rule": "link-quality"}),
        # two networks that meet within seconds: triangle routers drive to their goal points, in the fast step and
        # phase by phase (as in agent-assisted runs with several base stations)
        *(WarmUp(f"triangular deployment, {step} step", "self-spreading-6x6", two_bases, seconds=20.0, step=step)
          for step in ("compiled", "reference")),
        # and under a radio that does not decide links by distance: the link test at settling (issue #44)
        WarmUp("triangular deployment, multi-wall", "self-spreading-6x6", {**two_bases, "radio.model": "multi-wall"},
               seconds=20.0),
        WarmUp("batch self-spreading", "self-spreading-6x6", seeds=(1, 2)),
        WarmUp("large runs: the threaded kernels", "self-spreading-6x6", threaded=True, first=True),
    ]
