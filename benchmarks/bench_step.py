"""Robot-steps per second of the full self-spreading step for N = 30, 3 000 and 100 000 (README table).

Run: ``.venv/bin/python benchmarks/bench_step.py`` (or ``make bench``). Targets on the project's 2-core machine:
N = 3 000 at >= 1 000 steps/s and N = 100 000 at >= 10 steps/s. ``--rules``: instead, the per-step cost of each of
self-spreading's walk, stop and triangle rules against the paper's rule on the same scenario
(``bench_spreading_rules.py``, whose options follow ``--rules``).
"""

from __future__ import annotations

import argparse
import json

from amronet.sim.bench import run_bench

CASES = ((30, 5000), (3000, 1000), (100_000, 30))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--map", default="hospital_section")
    parser.add_argument("--json", action="store_true")
    parser.add_argument("--rules", nargs=argparse.REMAINDER, help="the rules' tables (bench_spreading_rules.py)")
    args = parser.parse_args()
    if args.rules is not None:
        from bench_spreading_rules import main as rules  # (this folder is on the path when run as a script)

        rules(args.rules)
        return
    rows = [run_bench(robots=n, steps=steps, map_name=args.map) for n, steps in CASES]
    if args.json:
        print(json.dumps(rows, indent=2))
        return
    phases = list(rows[0]["phase_share"])  # sense+decide+move and radio with the compiled step
    print("| N | threads | map scale | mean degree | steps/s | robot-steps/s | " + " | ".join(phases) + " |")
    print("|---:|---:|---:|---:|---:|---:|" + "---:|" * len(phases))
    for r in rows:
        shares = " | ".join(f"{r['phase_share'][k]:.0%}" for k in phases)
        print(f"| {r['robots']:,} | {r['threads']} | {r['map_scale']:.2f} | {r['mean_degree']:.1f} | "
              f"{r['steps_per_s']:,.1f} | {r['robot_steps_per_s']:,} | {shares} |")

if __name__ == "__main__":
    main()
