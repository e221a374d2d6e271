"""Time how long the ``amronet`` command takes to answer when it has nothing to simulate.

Run: ``.venv/bin/python benchmarks/bench_startup.py [--repeats N]``. Each command runs ``N`` times (default 5) in
a fresh process (``python -m amronet.cli``, the same as the ``amronet`` script); the table gives the median and the
spread of the wall times and the median CPU time (user + system, of the child: steadier than wall time on a
shared machine). The commands: ``--help``, ``run --help``, a run of a scenario file that does not exist, and runs of
scenario files with a bad field, an unknown key, an unknown algorithm and an unknown map (each refused with one
line, exit status 2). The target is half a second or less for each; ``tests/test_cli_startup.py`` checks the cause
(which libraries and kernels those commands import), not the time.
"""

from __future__ import annotations

import argparse
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

BAD_FIELD = "map: obstacles-6x6\nbase_stations: [{x: 0.5, y: 0.5}]\nrouters: {count: -3}\n"
"""A scenario whose ``routers.count`` is negative: refused by the schema."""
BAD = {"bad field": BAD_FIELD, "unknown key": BAD_FIELD.replace("routers: {count: -3}", "robots: 3"),
       "unknown algorithm": BAD_FIELD.replace("routers: {count: -3}", "algorithm: {name: nope}"),
       "unknown map": BAD_FIELD.replace("obstacles-6x6", "nope").replace("routers: {count: -3}\n", "")}
"""The refused scenarios timed, by what is wrong with them."""


def commands(folder: Path) -> dict[str, list[str]]:
    """The commands timed, by name (arguments after ``amronet``)."""
    out = str(folder / "out")
    cmds = {"--help": ["--help"], "run --help": ["run", "--help"],
            "run (no such file)": ["run", str(folder / "nonexistent.yaml"), "--out", out]}
    for what, text in BAD.items():
        path = folder / f"{what.replace(' ', '-')}.yaml"
        path.write_text(text, encoding="utf-8")
        cmds[f"run ({what})"] = ["run", str(path), "--out", out]
    return cmds


def wall_and_cpu_times(args: list[str], repeats: int) -> tuple[list[float], list[float]]:
    """Wall and CPU seconds of ``repeats`` runs of ``amronet ARGS``, each in a fresh process."""
    walls, cpus = [], []
    for _ in range(repeats):
        before = resource.getrusage(resource.RUSAGE_CHILDREN)
        t = time.perf_counter()
        subprocess.run([sys.executable, "-m", "amronet.cli", *args], capture_output=True, check=False)
        walls.append(time.perf_counter() - t)
        after = resource.getrusage(resource.RUSAGE_CHILDREN)
        cpus.append(after.ru_utime + after.ru_stime - before.ru_utime - before.ru_stime)
    return walls, cpus


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=5)
    args = ap.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        print(f"wall seconds over {args.repeats} runs each (a fresh process each)\n")
        print(f"{'command':<28} {'median':>7} {'min':>7} {'max':>7} {'cpu':>7}")
        for name, argv in commands(Path(tmp)).items():
            times, cpus = wall_and_cpu_times(argv, args.repeats)
            print(f"{name:<28} {statistics.median(times):7.3f} {min(times):7.3f} {max(times):7.3f} "
                  f"{statistics.median(cpus):7.3f}")


if __name__ == "__main__":
    main()
