"""The command line answers ``--help`` and refuses a missing scenario without importing numba, scipy or matplotlib.

Structural, not timed: each case runs in a fresh process and lists the heavy libraries it imported
(``benchmarks/bench_startup.py`` times the same commands). ``import amronet`` is light too, and still sets numba up
for amronet (its cache folder, its thread pool) the moment numba is imported (:mod:`amronet.numba_setup`).
"""

from __future__ import annotations

import json
import os
import subprocess
import sys

import pytest

HEAVY = ("numba", "scipy", "matplotlib")

_PROBE = """
import json, sys
from amronet.cli.main import main
try:
    status = main(json.loads(sys.argv[1]))
except SystemExit as stop:
    status = stop.code
print(json.dumps({"status": status, "modules": sorted({m.split(".")[0] for m in sys.modules})}))
"""


def _probe(code: str, *args: str, env: dict[str, str] | None = None) -> dict:
    proc = subprocess.run([sys.executable, "-c", code, *args], capture_output=True, text=True, timeout=120, env=env)
    assert proc.returncode == 0, proc.stderr[-3000:]
    return json.loads(proc.stdout.strip().splitlines()[-1])


@pytest.mark.parametrize("argv", [
    ["--help"],
    ["run", "--help"],
    ["compile", "--help"],
    ["run", "{missing}", "--out", "{out}"],
    ["run", "{missing}", "--out", "{out}", "--set", "radio.model=multi-wall"],
    ["run", "--preset", "self-spreading-6x6", "--out", "{out}", "--set", "radio.r_c"],
])
def test_answering_or_refusing_imports_no_heavy_library(argv, tmp_path):
    args = [a.format(missing=tmp_path / "nonexistent.yaml", out=tmp_path / "out") for a in argv]
    found = _probe(_PROBE, json.dumps(args))
    heavy = sorted(set(HEAVY) & set(found["modules"]))
    assert heavy == [], f"amronet {' '.join(argv)} imported {heavy}"
    assert found["status"] in (0, 2)
    assert not (tmp_path / "out").exists()


def test_the_public_names_load_on_first_use():
    code = """
import json, sys
import amronet, amronet.scenario
light = "numba" not in sys.modules
names = [n for mod in (amronet, amronet.scenario) for n in mod.__all__ if not hasattr(mod, n)]
from amronet import Scenario, Simulation, load_scenario, run
from amronet.sim.api import run as api_run
print(json.dumps({"light": light, "missing": names, "same": run is api_run and amronet.run is run}))
"""
    found = _probe(code)
    assert found == {"light": True, "missing": [], "same": True}


@pytest.mark.parametrize("numba_first", [False, True])
def test_numba_is_set_up_for_amronet_whoever_imports_it_first(numba_first, tmp_path):
    code = f"""
import json, sys
{"import numba" if numba_first else ""}
import amronet
light = "numba" not in sys.modules
import numba
from amronet import kernel_cache
print(json.dumps({{"light": light, "cache": numba.config.CACHE_DIR, "folder": str(kernel_cache._folder),
                  "threads": numba.config.THREADING_LAYER}}))
"""
    env = {k: v for k, v in os.environ.items() if k not in ("NUMBA_CACHE_DIR", "NUMBA_THREADING_LAYER")}
    env["XDG_CACHE_HOME"] = str(tmp_path)
    found = _probe(code, env=env)
    assert found["light"] is not numba_first
    assert found["folder"].startswith(str(tmp_path / "amronet" / "numba-"))
    assert found["cache"] == found["folder"]
    assert found["threads"] == "forksafe"
