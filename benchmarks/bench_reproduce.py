"""Wall time of the paper's four figures at full size (target: one minute together on the 2-core machine).

Run: ``.venv/bin/python benchmarks/bench_reproduce.py [--only fig10,fig11]``. Every figure runs from scratch
into a temporary folder with all cores, committing every run to a fresh result store as ``amronet reproduce``
does; the numbers go into the README.
"""

from __future__ import annotations

import argparse
import tempfile
import time
from pathlib import Path

from amronet.experiments.fig5 import run_fig5
from amronet.experiments.fig7 import run_fig7
from amronet.experiments.fig10 import run_coverage_over_time
from amronet.experiments.options import RunOptions


def _options(store: Path) -> RunOptions:
    return RunOptions(show_progress=False, store=store)


FIGURES = {
    "fig5": lambda out, store: run_fig5(out, options=_options(store)),
    "fig7": lambda out, store: run_fig7(out, options=_options(store)),
    "fig10": lambda out, store: run_coverage_over_time("fig10", out, options=_options(store)),
    "fig11": lambda out, store: run_coverage_over_time("fig11", out, options=_options(store)),
}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--only", default=",".join(FIGURES), help="comma-separated figures")
    args = parser.parse_args()
    total = 0.0
    print("| figure | runs | wall time (s) |")
    print("|---|---:|---:|")
    with tempfile.TemporaryDirectory() as tmp:
        for name in args.only.split(","):
            start = time.perf_counter()
            report = FIGURES[name](Path(tmp) / name, Path(tmp) / f"{name}.sqlite")
            wall = time.perf_counter() - start
            total += wall
            print(f"| {name} | {len(report['rows'])} | {wall:.1f} |", flush=True)
    print(f"| all | | {total:.1f} |")


if __name__ == "__main__":
    main()
