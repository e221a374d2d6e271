"""Per-step cost of the Voronoi-cell baselines (VOR, Minimax, Lloyd) against self-spreading, N = 30 / 300 / 3 000.

Run: ``.venv/bin/python benchmarks/bench_voronoi.py [--rounds 3] [--steps 50]``. Each case is ``amronet bench``'s
full step (:func:`amronet.sim.bench.run_bench`: routers scattered over the scaled ``hospital_section``, about a
dozen neighbours each, sensing, deciding, moving with collisions, the radio) for ``--steps`` steps, two rounds of the
baselines' default 2.5 s rounds at the Bebot's speed: a baseline builds every cell in the first step of a round and
only drives in the others, so the mean over whole rounds is its cost. The algorithms alternate within each round of
the benchmark (A/B on a shared machine); every round's numbers are printed, with the median ratio to
self-spreading. ``decide`` is the share of the step spent in the controller (self-spreading's compiled step does
sense, decide and move in one pass: its share is the three together).
"""

from __future__ import annotations

import argparse
import statistics

from amronet.sim.bench import run_bench

ALGORITHMS = ("self-spreading", "vor", "minimax", "lloyd")
SIZES = (30, 300, 3000)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--steps", type=int, default=50)
    parser.add_argument("--map", default="hospital_section")
    args = parser.parse_args()
    ms: dict[tuple[int, str], list[float]] = {}
    share: dict[tuple[int, str], list[float]] = {}
    for _ in range(args.rounds):
        for n in SIZES:
            for algorithm in ALGORITHMS:
                r = run_bench(algorithm=algorithm, robots=n, steps=args.steps, map_name=args.map)
                ms.setdefault((n, algorithm), []).append(1000.0 * r["wall_s"] / r["steps"])
                phases = r["phase_share"]
                share.setdefault((n, algorithm), []).append(phases.get("decide", phases.get("sense+decide+move", 0)))
    print("| N | algorithm | ms per step, each round | median | ratio to self-spreading | decide share |")
    print("|---:|---|---|---:|---:|---:|")
    for n in SIZES:
        for algorithm in ALGORITHMS:
            rounds = ms[(n, algorithm)]
            ratios = [a / b for a, b in zip(rounds, ms[(n, "self-spreading")], strict=True)]
            print(f"| {n:,} | {algorithm} | {' / '.join(f'{v:.2f}' for v in rounds)} | "
                  f"{statistics.median(rounds):.2f} | {statistics.median(ratios):.1f}x | "
                  f"{statistics.median(share[(n, algorithm)]):.0%} |")


if __name__ == "__main__":
    main()
