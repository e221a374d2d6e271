"""Throughput of a sweep (runs per second, result store included): local process pool vs Dask LocalCluster.

A 1 000-run sweep of short runs (self-spreading on the 6 m x 6 m field, 30 routers, 2 simulated seconds: a few
milliseconds of simulation each), so what is measured is the machinery: submitting, pickling, collecting and
committing each run in its own SQLite transaction. Each executor writes into a fresh store.

    python benchmarks/bench_sweep.py [--runs 1000] [--workers N] [--time-limit 2]
"""

import argparse
import tempfile
import time
from pathlib import Path

from amronet.sweeps import DaskExecutor, LocalExecutor, default_workers, run_sweep, sweep_from_spec


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--runs", type=int, default=1000)
    ap.add_argument("--workers", type=int, default=default_workers())
    ap.add_argument("--time-limit", type=float, default=2.0)
    args = ap.parse_args()
    radii = [0.8, 0.9, 1.0, 1.1, 1.2]
    seeds = max(1, args.runs // len(radii))
    sweep = sweep_from_spec({"name": "bench", "base": "self-spreading-6x6",
                             "overrides": {"sim.time_limit": args.time_limit}, "grid": {"radio.r_c": radii},
                             "seeds": seeds})
    n = len(sweep.runs())
    print(f"{n} runs (self-spreading-6x6, {args.time_limit:g} s simulated each), {args.workers} workers")
    with tempfile.TemporaryDirectory() as tmp:
        # warm-up: compile numba kernels into the on-disk cache once, outside the timings
        warm = sweep_from_spec({"name": "warm", "base": "self-spreading-6x6",
                                "overrides": {"sim.time_limit": args.time_limit}, "seeds": 1})
        run_sweep(warm, Path(tmp) / "warm.sqlite", LocalExecutor(1), show_progress=False)
        candidates = [("local pool, 1 worker (in process)", lambda: LocalExecutor(1)),
                      (f"local pool, {args.workers} workers", lambda: LocalExecutor(args.workers)),
                      (f"Dask LocalCluster, {args.workers} workers", lambda: DaskExecutor(workers=args.workers))]
        for k, (name, make) in enumerate(candidates):
            start = time.perf_counter()
            with make() as executor:
                ready = time.perf_counter()
                report = run_sweep(sweep, Path(tmp) / f"{k}.sqlite", executor, show_progress=False)
            total = time.perf_counter() - start
            sweep_s = report.wall_time_s
            print(f"{name:<34} {n / sweep_s:8.1f} runs/s  ({sweep_s:.2f} s for the sweep; start-up "
                  f"{ready - start:.2f} s; {n / total:.1f} runs/s counting it)")


if __name__ == "__main__":
    main()
