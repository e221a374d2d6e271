"""Time amronet.optimum: the best placement, the proven bound and the gap within a time limit, on built-in maps.

Run: ``.venv/bin/python benchmarks/bench_optimum.py`` (two quick cases, about two minutes) or ``--targets`` (the
cases docs/optimum.md reports: ``office-32x32`` with the unit disk at 2 m and at 1 m, ``hospital_section`` with the
multi-wall radio at 1 m, about eleven minutes: the issue's three targets). ``--solver cp-sat`` solves the last phase
with OR-Tools CP-SAT (the ``optimum`` extra) instead of HiGHS. Each case prints the instance (sites, sites kept,
coverage rows), the best count and who found it, the proven lower bound and its parts, the gap, the wall time and
the process's CPU time (on a shared machine the CPU time says how much of the wall time the search had). A case that
reaches its time limit depends on the machine's speed (and on what else runs on it): HiGHS's search is
deterministic, its stopping time is not; CP-SAT's workers race, so its answers may differ between runs.
"""

from __future__ import annotations

import argparse
import os
import time

from amronet.optimum import find_optimum

QUICK = [
    ("office-32x32", (1.0, 1.0), 4.0, 2.0, None, 60.0),
    ("hospital_section", (3.0, 6.0), 4.0, 1.0, {"model": "multi-wall"}, 60.0),
]
"""(map, base, r_c, spacing, radio, time limit s)."""

TARGETS = [
    ("office-32x32", (1.0, 1.0), 4.0, 2.0, None, 60.0),
    ("office-32x32", (1.0, 1.0), 4.0, 1.0, None, 300.0),
    ("hospital_section", (3.0, 6.0), 4.0, 1.0, {"model": "multi-wall"}, 300.0),
]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--targets", action="store_true", help="the cases of docs/optimum.md (about eleven minutes)")
    ap.add_argument("--solver", default="highs", choices=["highs", "cp-sat"], help="the last phase's solver")
    args = ap.parse_args()
    cases = TARGETS if args.targets else QUICK
    load = os.getloadavg()[0] if hasattr(os, "getloadavg") else float("nan")
    print(f"{os.cpu_count()} cores, load average {load:.2f} at the start; solver {args.solver}\n")
    head = (f"{'map':<17} {'radio':<10} {'s/m':>4} {'sites':>6} {'kept':>5} {'rows':>6} {'best':>5} {'by':<15} "
            f"{'bound':>5} {'gap %':>6} {'LP':>6} {'cover':>5} {'hops':>5} {'limit':>6} {'solver s':>9} {'total s':>8} "
            f"{'cpu s':>6} {'load':>5}")
    print(head)
    for name, base, r_c, spacing, radio, limit in cases:
        t, cpu = time.perf_counter(), time.process_time()
        o = find_optimum(name, [base], r_c, spacing, radio=radio, time_limit=limit, solver=args.solver)
        total, cpu = time.perf_counter() - t, time.process_time() - cpu
        b, c = o.bounds, o.candidates
        gap = "inf" if o.gap is None else f"{100 * o.gap:.1f}"
        lp = "n/a" if b["lp_relaxation"] is None else f"{b['lp_relaxation']:.1f}"
        print(f"{name:<17} {o.radio['model']:<10} {spacing:>4g} {c['sites']:>6} {c['kept']:>5} {c['rows']:>6} "
              f"{o.count:>5} {o.source:<15} {o.lower:>5} {gap:>6} {lp:>6} {b['set_cover']['lower']:>5} "
              f"{max(b['hop_straight'], b['hop_lattice']):>5} {limit:>6g} {o.solver['seconds']:>9.1f} {total:>8.1f} "
              f"{cpu:>6.1f} {os.getloadavg()[0]:>5.1f}",
              flush=True)
        assert o.verified["coverage"] == 1.0 and o.verified["connected"], o.verified


if __name__ == "__main__":
    main()
