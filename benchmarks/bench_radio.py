"""The cost of a real radio, as ratios to the unit disk measured in the same process (README table).

Run: ``.venv/bin/python benchmarks/bench_radio.py`` (``--robots 300``: the radio step of fewer routers). Three
measurements, each against its unit-disk peer:

* the radio step (building the neighbour table with link quality) of 3 000 routers scattered over the reachable
  free space of ``hospital_section``, scaled as ``amronet bench`` scales it (0.25 m² per robot, ``r_c`` = 1 m),
  for ``multi-wall`` (no shadowing, the model's default), ``multi-wall`` with 5 dB shadowing and ``log-distance``
  (5 dB shadowing, its default), with every router moving between steps and with 5 % of them moving (the media
  reuse the margins of links whose ends stood still) — target: multi-wall at most 6x the unit disk with all moving,
  4x with 5 % moving;
* coverage of 30 nodes on ``obstacles-6x6`` (the positions of a self-spreading run after 60 s, ``r_c`` = 1 m) —
  target: multi-wall at most 10x the unit-disk raster;
* the signal map of one node over the unscaled ``hospital_section`` (``r_c`` = 4 m, multi-wall) — target: under
  50 ms.

Each timing is the best of several repeats after a warm-up call (numba compiles on first use, cached on disk).
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import math
import time
from collections.abc import Callable

import numpy as np

from amronet.engine.propagation import LinkBudget
from amronet.engine.radio import make_medium
from amronet.engine.robots import Role
from amronet.scenario import load_scenario
from amronet.sim.simulation import Simulation
from amronet.world.builtin import resolve_map


def best_of(fn: Callable[[], object], repeats: int) -> float:
    """Best wall time of ``repeats`` calls of ``fn`` after one warm-up call, in seconds."""
    fn()
    best = math.inf
    for _ in range(repeats):
        t = time.perf_counter()
        fn()
        best = min(best, time.perf_counter() - t)
    return best


def radio_step(robots: int = 3000, repeats: int = 20) -> list[dict]:
    """Neighbour-table build of ``robots`` routers on scaled ``hospital_section`` under each model."""
    omap = resolve_map("hospital_section")
    area = np.count_nonzero(omap.free) * omap.resolution**2
    scale = max(1.0, math.sqrt(robots * 0.25 / area))
    omap = dataclasses.replace(omap, resolution=omap.resolution * scale, _cache={})
    rng = np.random.default_rng(0)
    rows, cols = np.nonzero(omap.free)
    pick = rng.choice(len(rows), size=robots, replace=False)
    xy = omap.cell_centres(rows[pick], cols[pick]) + rng.uniform(-0.4, 0.4, (robots, 2)) * omap.resolution
    cases = [("unit-disk", LinkBudget(r_c=1.0)),
             ("multi-wall", LinkBudget(r_c=1.0, exponent=2.0, wall_db=6.9)),
             ("multi-wall", LinkBudget(r_c=1.0, exponent=2.0, wall_db=6.9, shadowing_db=5.0)),
             ("log-distance", LinkBudget(r_c=1.0, exponent=2.5, shadowing_db=5.0))]
    # every robot moves between steps (two position sets in turn), or 5 % of them do (a deployed network with
    # agents and explorers moving: the media reuse the margins of links whose ends stood still)
    other = xy + rng.uniform(-0.02, 0.02, xy.shape)
    few = xy.copy()
    movers = rng.choice(robots, size=robots // 20, replace=False)
    few[movers] = other[movers]
    out = []
    for model, budget in cases:
        row = {"model": model, "shadowing_db": budget.shadowing_db, "map_resolution_m": omap.resolution}
        for name, second in (("ms", other), ("ms_5pct_moving", few)):
            medium = make_medium(model, budget, omap, rng=np.random.default_rng(1))
            turn = [0]

            def step(m=medium, pair=(xy, second), turn=turn) -> None:
                turn[0] ^= 1
                m.update(pair[turn[0]])

            row[name] = best_of(step, repeats) * 1e3
        row["mean_degree"] = float(medium.update(xy).degree.mean())
        out.append(row)
    return out


def coverage(repeats: int = 20) -> list[dict]:
    """Coverage of the 30 nodes of a self-spreading run on ``obstacles-6x6`` under each model."""
    sim = Simulation(load_scenario("self-spreading-obstacles-6x6"), 1)
    for _ in range(600):
        sim.step()
    xy = sim.swarm.xy[sim.swarm.role != Role.AGENT]
    area, omap = sim.world.coverage, sim.world.omap
    out = []
    for model, budget in (("unit-disk", LinkBudget(r_c=1.0)),
                          ("multi-wall", LinkBudget(r_c=1.0, exponent=2.0, wall_db=6.9)),
                          ("multi-wall", LinkBudget(r_c=1.0, exponent=2.0, wall_db=6.9, shadowing_db=5.0)),
                          ("log-distance", LinkBudget(r_c=1.0, exponent=2.5, shadowing_db=5.0))):
        medium = make_medium(model, budget, omap, rng=np.random.default_rng(1))

        def cold(m=medium) -> None:  # every node new to the medium (its cache of heard cells emptied)
            m.heard.forget()
            m.coverage(area, xy)

        out.append({"model": model, "shadowing_db": budget.shadowing_db, "ms": best_of(cold, repeats) * 1e3,
                    "ms_still": best_of(lambda m=medium: m.coverage(area, xy), repeats) * 1e3,
                    "coverage": medium.coverage(area, xy)})
    return out


def signal_map(repeats: int = 5) -> dict:
    """The signal map of one node over ``hospital_section`` under multi-wall."""
    omap = resolve_map("hospital_section")
    rows, cols = np.nonzero(omap.free)
    node = omap.cell_centres(rows[len(rows) // 2:len(rows) // 2 + 1], cols[len(rows) // 2:len(rows) // 2 + 1])
    medium = make_medium("multi-wall", LinkBudget(r_c=4.0, exponent=2.0, wall_db=6.9), omap)
    seconds = best_of(lambda: medium.signal_dbm(omap, node), repeats)
    return {"cells": int(omap.cells.size), "ms": seconds * 1e3}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--json", action="store_true")
    parser.add_argument("--robots", type=int, default=3000, help="routers of the radio step (default 3000)")
    args = parser.parse_args()
    if args.robots < 2:
        parser.error(f"--robots must be at least 2, got {args.robots}")
    report = {"radio_step": radio_step(args.robots), "coverage": coverage(), "signal_map": signal_map()}
    if args.json:
        print(json.dumps(report, indent=2))
        return
    rows = report["radio_step"]
    base, base5 = rows[0]["ms"], rows[0]["ms_5pct_moving"]
    print(f"\nradio step, N = {args.robots:,}, hospital_section scaled\n| model | shadowing (dB) | all move: ms "
          "| ratio | 5 % move: ms | ratio |\n|---|---:|---:|---:|---:|---:|")
    for r in rows:
        print(f"| {r['model']} | {r['shadowing_db']:g} | {r['ms']:.3f} | {r['ms'] / base:.1f}x | "
              f"{r['ms_5pct_moving']:.3f} | {r['ms_5pct_moving'] / base5:.1f}x |")
    rows = report["coverage"]
    base = rows[0]["ms"]
    print("\ncoverage, 30 nodes, obstacles-6x6\n| model | shadowing (dB) | nodes new: ms | ratio | nodes still: ms "
          "| ratio |\n|---|---:|---:|---:|---:|---:|")
    for r in rows:
        print(f"| {r['model']} | {r['shadowing_db']:g} | {r['ms']:.3f} | {r['ms'] / base:.1f}x | "
              f"{r['ms_still']:.3f} | {r['ms_still'] / base:.1f}x |")
    s = report["signal_map"]
    print(f"\nsignal map, one node, hospital_section ({s['cells']:,} cells): {s['ms']:.1f} ms")


if __name__ == "__main__":
    main()
