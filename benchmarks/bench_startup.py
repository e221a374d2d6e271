"""Time how long the ``amronet`` command takes to answer when it has nothing to simulate.

Run: ``.venv/bin/python benchmarks/bench_startup.py [--repeats N]``. Each command runs ``N`` times (default 5) in
a fresh process (``python -m amronet.cli``, the same as the ``amronet`` script); the table gives the median and the
spread of the wall times. The commands: ``--help``, ``run --help``, a run of a scenario file that does not exist,
and one of a scenario file with a bad field (both refused with one line, exit status 2). The target is half a second
or less for each; ``tests/test_cli_startup.py`` checks the cause (which libraries those commands import), not the
time.
"""

from __future__ import annotations

import argparse
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

BAD_FIELD = "map: obstacles-6x6\nbase_stations: [{x: 0.5, y: 0.5}]\nrouters: {count: -3}\n"
"""A scenario whose ``routers.count`` is negative: refused by the schema."""


def commands(folder: Path) -> dict[str, list[str]]:
    """The commands timed, by name (arguments after ``amronet``)."""
    bad = folder / "bad-field.yaml"
    bad.write_text(BAD_FIELD, encoding="utf-8")
    out = str(folder / "out")
    return {"--help": ["--help"], "run --help": ["run", "--help"],
            "run (no such file)": ["run", str(folder / "nonexistent.yaml"), "--out", out],
            "run (bad field)": ["run", str(bad), "--out", out]}


def wall_times(args: list[str], repeats: int) -> list[float]:
    """Wall seconds of ``repeats`` runs of ``amronet ARGS``, each in a fresh process."""
    times = []
    for _ in range(repeats):
        t = time.perf_counter()
        subprocess.run([sys.executable, "-m", "amronet.cli", *args], capture_output=True, check=False)
        times.append(time.perf_counter() - t)
    return times


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=5)
    args = ap.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        print(f"wall seconds over {args.repeats} runs each (a fresh process each)\n")
        print(f"{'command':<22} {'median':>7} {'min':>7} {'max':>7}")
        for name, argv in commands(Path(tmp)).items():
            times = wall_times(argv, args.repeats)
            print(f"{name:<22} {statistics.median(times):7.3f} {min(times):7.3f} {max(times):7.3f}")


if __name__ == "__main__":
    main()
