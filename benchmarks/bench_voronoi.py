"""Per-step cost of the Voronoi-cell baselines (VOR, Minimax, Lloyd) against self-spreading, N = 30 / 300 / 3 000.

Run: ``.venv/bin/python benchmarks/bench_voronoi.py [--rounds 3] [--steps 50]``. Each case is ``amronet bench``'s
full step (:func:`amronet.sim.bench.run_bench`: routers scattered over the scaled ``hospital_section``, about a
dozen neighbours each, sensing, deciding, moving with collisions, the radio) for ``--steps`` steps, two rounds of the
baselines' default 2.5 s rounds at the Bebot's speed: a baseline builds every cell in the first step of a round and
only drives in the others, so the mean over whole rounds is its cost. The algorithms alternate within each round of
the benchmark (A/B on a shared machine); in each round a case runs ``REPEATS[N]`` times and counts with the
median of them (a 30-robot case takes milliseconds: one pause of the machine would be its number); every round's
numbers are printed, with the median ratio to self-spreading. ``--clock cpu`` (the default) times the steps in this
process's CPU time (``time.process_time`` in place of the benchmark's and the loop's wall clock: other jobs on a
shared machine do not count), ``--clock wall`` in wall time. ``decide`` is the share of the step spent in the
controller (self-spreading's compiled step does sense, decide and move in one pass: its share is the three
together).
"""

from __future__ import annotations

import argparse
import statistics
import time

import amronet.sim.bench as bench_module
import amronet.sim.loop as loop_module
from amronet.sim.bench import run_bench

ALGORITHMS = ("self-spreading", "vor", "minimax", "lloyd")
SIZES = (30, 300, 3000)
REPEATS = {30: 10, 300: 3, 3000: 1}
"""Runs of a case in each round (their median counts)."""


class _CpuClock:
    """The clock ``run_bench`` and the loop read (``time.perf_counter``), read as this process's CPU time."""

    perf_counter = staticmethod(time.process_time)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--steps", type=int, default=50)
    parser.add_argument("--map", default="hospital_section")
    parser.add_argument("--clock", choices=("cpu", "wall"), default="cpu")
    args = parser.parse_args()
    if args.clock == "cpu":
        bench_module.time = loop_module.time = _CpuClock  # type: ignore[assignment]
    ms: dict[tuple[int, str], list[float]] = {}
    share: dict[tuple[int, str], list[float]] = {}
    for _ in range(args.rounds):
        for n in SIZES:
            for algorithm in ALGORITHMS:
                runs = [run_bench(algorithm=algorithm, robots=n, steps=args.steps, map_name=args.map)
                        for _ in range(REPEATS[n])]
                step_ms = [1000.0 / r["steps_per_s"] for r in runs]  # not wall_s: it is rounded to 1 ms
                ms.setdefault((n, algorithm), []).append(statistics.median(step_ms))
                phases = runs[step_ms.index(statistics.median_low(step_ms))]["phase_share"]
                share.setdefault((n, algorithm), []).append(phases.get("decide", phases.get("sense+decide+move", 0)))
    print("| N | algorithm | ms per step, each round | median | median ratio to self-spreading | decide share |")
    print("|---:|---|---|---:|---:|---:|")
    for n in SIZES:
        for algorithm in ALGORITHMS:
            rounds = ms[(n, algorithm)]
            ratios = [a / b for a, b in zip(rounds, ms[(n, "self-spreading")], strict=True)]
            print(f"| {n:,} | {algorithm} | {' / '.join(f'{v:.3f}' for v in rounds)} | "
                  f"{statistics.median(rounds):.3f} | {statistics.median(ratios):.2f}x | "
                  f"{statistics.median(share[(n, algorithm)]):.0%} |")


if __name__ == "__main__":
    main()
