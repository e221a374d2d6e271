"""Per-step cost of self-spreading's rules against the paper's rule on the same scenario (a table per rule kind).

* walk rules (``algorithm.params.walk``): the scenario of ``amronet reproduce walks`` on a map
  (:func:`amronet.experiments.walks.walk_scenario`: its routers, radio and recording), each rule against ``random``;
* the ``link-quality`` stop rule against ``distance``, on the same scenario with the random walk;
* the ``link-quality`` triangle rule against ``geometric``, on ``self-spreading-office`` (two base stations, every
  triangle deployed: ``triangular: none``), where triangle routers search.

Each run is the loop's whole run (:meth:`amronet.sim.Simulation.run`: stretches, records and coverage as a user's run
takes them) for ``--seconds`` simulated seconds, seed 1, timed in CPU seconds of this process and divided by the steps
taken. The rules of a kind run one after another in each round, ``--rounds`` rounds: every round's ratio to the
paper's rule is printed, and their median (a shared machine's noise shows as spread between rounds). A first run of
every case loads (or compiles) the kernels before any timing.

Run: ``.venv/bin/python benchmarks/bench_spreading_rules.py`` (or ``benchmarks/bench_step.py --rules``).
"""

from __future__ import annotations

import argparse
import statistics
import time
from typing import Any

from amronet.algorithms.self_spreading.walks import WALKS
from amronet.experiments.walks import WALK_MAPS, walk_scenario
from amronet.scenario import load_scenario
from amronet.sim import Simulation

__all__ = ["cases", "main", "measure", "table"]

SEED = 1


def cases(map_name: str, seconds: float) -> dict[str, list[tuple[str, Any, dict[str, Any]]]]:
    """Per rule kind, ``(label, scenario, overrides)`` of each rule, the paper's rule first."""
    walks = [(f"walk {w}", walk_scenario(map_name, w, seconds), {}) for w in WALKS]
    random = walk_scenario(map_name, "random", seconds)
    stops = [(f"stop_rule {rule}", random, {"algorithm.params.stop_rule": rule})
             for rule in ("distance", "link-quality")]
    office = {"sim.time_limit": seconds, "algorithm.params.triangular": "none"}
    triangles = [(f"triangle_rule {rule}", "self-spreading-office", {**office, "algorithm.params.triangle_rule": rule})
                 for rule in ("geometric", "link-quality")]
    return {f"walk rules ({map_name})": walks, f"stop rules ({map_name})": stops,
            "triangle rules (self-spreading-office)": triangles}


def measure(scenario: Any, overrides: dict[str, Any]) -> tuple[float, int, bool]:
    """``(CPU µs per step, steps, compiled step?)`` of one whole run."""
    sim = Simulation(load_scenario(scenario, overrides), SEED)
    t0 = time.process_time()
    sim.run()
    return (time.process_time() - t0) / max(sim.steps, 1) * 1e6, sim.steps, sim.compiled is not None


def table(kind: str, rows: list[tuple[str, Any, dict[str, Any]]], rounds: int) -> list[str]:
    """The markdown table of one rule kind: µs per step per round, and the ratio to the first (paper's) rule."""
    for _, scenario, overrides in rows:  # load (or compile) the kernels and the map
        Simulation(load_scenario(scenario, {**overrides, "sim.time_limit": 1.0}), SEED).run()
    cost: dict[str, list[float]] = {label: [] for label, _, _ in rows}
    steps: dict[str, int] = {}
    compiled: dict[str, bool] = {}
    for _ in range(rounds):
        for label, scenario, overrides in rows:
            us, steps[label], compiled[label] = measure(scenario, overrides)
            cost[label].append(us)
    paper = rows[0][0]
    lines = [f"### {kind}", "", "| rule | compiled | steps | µs/step per round | ratio to "
             f"{paper.split()[-1]} per round | median ratio |", "|---|---|---:|---|---|---:|"]
    for label, values in cost.items():
        ratios = [v / p for v, p in zip(values, cost[paper], strict=True)]
        lines.append(f"| {label} | {'yes' if compiled[label] else 'no'} | {steps[label]} | "
                     f"{' / '.join(f'{v:.0f}' for v in values)} | {' / '.join(f'{r:.2f}' for r in ratios)} | "
                     f"{statistics.median(ratios):.2f} |")
    return [*lines, ""]


def main(argv: list[str] | None = None) -> None:
    """Print one table per rule kind."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--map", default="hospital_section", choices=sorted(WALK_MAPS))
    parser.add_argument("--seconds", type=float, default=120.0, help="simulated seconds per run (default 120)")
    parser.add_argument("--rounds", type=int, default=3, help="rounds (default 3)")
    parser.add_argument("--kinds", default="walk,stop,triangle", help="which tables: walk, stop, triangle")
    args = parser.parse_args(argv)
    wanted = args.kinds.split(",")
    for kind, rows in cases(args.map, args.seconds).items():
        if kind.split()[0] in wanted:
            print("\n".join(table(kind, rows, args.rounds)), flush=True)


if __name__ == "__main__":
    main()
