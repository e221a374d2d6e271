"""Run every benchmark in this folder, one after another."""

import runpy
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent

for script in sorted(HERE.glob("bench_*.py")):
    print(f"\n## {script.stem}\n", flush=True)
    sys.argv = [str(script)]
    try:
        runpy.run_path(str(script), run_name="__main__")
    except SystemExit as stop:  # e.g. bench_peers without its optional extra (Mesa): skip it, run the others
        if stop.code not in (None, 0):
            print(f"skipped {script.stem} (exit {stop.code}): see the message above", flush=True)
