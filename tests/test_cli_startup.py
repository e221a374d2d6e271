"""The command line answers ``--help`` and refuses a missing or bad scenario without importing numba or scipy.

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


_REFUSED = {  # a scenario file's bad field -> the one line that refuses it (unchanged by loading lazily)
    "foo: 1": "foo: unknown key; allowed keys here: name, description, map, algorithm, radio, base_stations, "
              "routers, agents, sim, faults",
    "radio: {r_c: -1}": "radio.r_c: input should be greater than 0 (got -1)",
    "routers: {count: x}": "routers.count: input should be a valid integer (got 'x')",
    "radio: {model: foo}": "radio.model: unknown radio model 'foo'; choose one of: log-distance, multi-wall, unit-disk",
    "radio: {wall_db: 3}": "radio.wall_db: the unit-disk model has no walls; use radio.model=multi-wall or leave "
                           "wall_db out",
    "algorithm: {name: nope}": "algorithm.name: unknown algorithm 'nope'; choose one of: agent-assisted, dssa, ",
    "algorithm: {name: agent-assisted, params: {nope: 1}}": "algorithm.params.nope: unknown key; allowed keys here: ",
    "algorithm: {params: {triangular: sideways}}": "algorithm.params.triangular: input should be 'off', 'none', "
                                                   "'global' or 'local' (got 'sideways')",
    "sim: {coverage_target: 2.0}": "sim.coverage_target: 2.0 is not a fraction in (0, 1] (with a decimal point) nor "
                                   "off; give e.g. 0.99, or off for no target",
}
"""Each is refused by the schema; the message was taken from the code that imported every algorithm's kernels."""

_PROBE_EVERY_MODULE = _PROBE.replace('sorted({m.split(".")[0] for m in sys.modules})', "sorted(sys.modules)")
""":data:`_PROBE`, listing every module imported (``amronet.engine.radio``), not only the top-level packages."""

_KERNELS = ("amronet.engine.radio", "amronet.engine.robots", "amronet.engine.propagation", "amronet.algorithms.base")
"""Modules of the engine (numba kernels, SciPy) that checking a scenario does not need."""


def _heavy_modules(modules: list[str]) -> list[str]:
    """The heavy libraries, amronet's kernel modules and the algorithms' controllers among ``modules``."""
    return sorted(m for m in modules if m.split(".")[0] in HEAVY or m in _KERNELS
                  or (m.startswith("amronet.algorithms.") and m.rsplit(".", 1)[-1] in ("controller", "kernels")))


@pytest.mark.parametrize("bad", sorted(_REFUSED))
def test_a_refused_scenario_imports_no_kernel(bad, tmp_path):
    """A scenario refused by its schema is refused before numba, SciPy or any algorithm's controller is imported."""
    path = tmp_path / "bad.yaml"
    path.write_text(f"map: obstacles-6x6\nbase_stations: [{{x: 0.5, y: 0.5}}]\n{bad}\n", encoding="utf-8")
    args = ["run", str(path), "--out", str(tmp_path / "out")]
    proc = subprocess.run([sys.executable, "-c", _PROBE_EVERY_MODULE, json.dumps(args)],
                          capture_output=True, text=True, timeout=120)
    found = json.loads(proc.stdout.strip().splitlines()[-1])
    assert found["status"] == 2
    assert proc.stderr.strip().startswith(f"amronet: error: {_REFUSED[bad]}"), proc.stderr
    assert len(proc.stderr.strip().splitlines()) == 1
    assert "amronet.scenario.schema" in found["modules"]  # (every module listed, not only the packages)
    assert _heavy_modules(found["modules"]) == []
    assert not (tmp_path / "out").exists()


def test_an_unknown_map_name_is_refused_before_any_map_code(tmp_path):
    """``map: nope`` is refused by the scenario's check of the built-in names: no NumPy, no image reader, no kernels."""
    path = tmp_path / "bad.yaml"
    path.write_text("map: nope\nbase_stations: [{x: 0.5, y: 0.5}]\n", encoding="utf-8")
    args = ["run", str(path), "--out", str(tmp_path / "out")]
    proc = subprocess.run([sys.executable, "-c", _PROBE_EVERY_MODULE, json.dumps(args)],
                          capture_output=True, text=True, timeout=120)
    found = json.loads(proc.stdout.strip().splitlines()[-1])
    assert found["status"] == 2
    assert proc.stderr.strip() == ("amronet: error: map: unknown map 'nope'; use a built-in name (amronet maps list: "
                                   "open-6x6, obstacles-6x6, open-32x32, office-32x32, autolab, cave, depot, "
                                   "hospital_section) or a path to a ROS map_server YAML")
    assert _heavy_modules(found["modules"]) == []
    assert not {"PIL", "amronet.world.builtin", "amronet.world.space"} & set(found["modules"])
    assert not (tmp_path / "out").exists()


def test_algorithms_are_declared_light_and_their_controllers_load_on_lookup():
    code = """
import json, sys
from amronet.algorithms import ALGORITHMS
from amronet.algorithms.declaration import DECLARATIONS
names, light = list(ALGORITHMS), "numba" not in sys.modules
loaded_before = [m for m in sys.modules if m.endswith(".controller")]
dssa = ALGORITHMS["dssa"]
print(json.dumps({"names": names, "declared": list(DECLARATIONS), "light": light, "before": loaded_before,
                  "after": sorted(m for m in sys.modules if m.endswith(".controller")), "class": dssa.__name__}))
"""
    found = _probe(code)
    assert found["names"] == found["declared"] and {"dssa", "self-spreading", "agent-assisted"} <= set(found["names"])
    assert found["light"] and found["before"] == []
    assert found["after"] == ["amronet.algorithms.dssa.controller"] and found["class"] == "DSSA"


def test_every_declaration_says_what_its_controller_does():
    """A declaration's model is its controller's ``Params``; scenario-facing traits live in the declaration only."""
    from amronet.algorithms import ALGORITHMS
    from amronet.algorithms.declaration import DECLARATIONS

    for name, declared in DECLARATIONS.items():
        controller = ALGORITHMS[name]
        assert controller.name == name and controller.__module__ == declared.controller
        assert controller.Params is declared.params
        assert not {"scenario_defaults", "follows_paths"} & set(dir(controller)), f"{name}: declare them instead"


def test_the_radio_traits_are_the_radio_models():
    """The scenario's table of radio models (:mod:`amronet.engine.radio_traits`) is what :data:`MEDIA` registers."""
    from dataclasses import fields

    from amronet.engine.radio import MEDIA
    from amronet.engine.radio_traits import RADIO_TRAITS

    assert sorted(RADIO_TRAITS) == sorted(n for n, cls in MEDIA.items() if cls.__module__ == "amronet.engine.radio")
    for name, traits in RADIO_TRAITS.items():
        for field in fields(traits):
            assert getattr(MEDIA[name], field.name) == getattr(traits, field.name), (name, field.name)


def test_a_declared_name_is_known_before_its_module_is_imported(tmp_path, monkeypatch):
    from amronet.errors import ScenarioError
    from amronet.registry import Registry

    reg: Registry[type] = Registry("gadget")
    (tmp_path / "gadget_mod.py").write_text("from tests_reg import REG\n@REG.register('spoon')\nclass Spoon: ...\n")
    (tmp_path / "silent_mod.py").write_text("")
    monkeypatch.syspath_prepend(str(tmp_path))
    monkeypatch.setitem(sys.modules, "tests_reg", type(sys)("tests_reg"))
    sys.modules["tests_reg"].REG = reg
    reg.declare("spoon", "gadget_mod")
    reg.declare("fork", "silent_mod")
    assert "spoon" in reg and list(reg) == ["spoon", "fork"] and len(reg) == 2 and "gadget_mod" not in sys.modules
    with pytest.raises(ScenarioError, match="unknown gadget 'knife'; choose one of: fork, spoon"):
        reg.lookup("knife", "kitchen")
    assert reg["spoon"].__name__ == "Spoon" and reg["spoon"].name == "spoon"
    with pytest.raises(LookupError, match="silent_mod did not register the gadget 'fork'"):
        reg["fork"]
    with pytest.raises(ValueError, match="declared twice"):
        reg.declare("spoon", "elsewhere")
    for module in ("gadget_mod", "silent_mod"):
        sys.modules.pop(module, None)


def test_a_controller_registered_at_run_time_is_declared_by_its_class():
    """Code that defines a controller and registers it (without a declaration) can still run scenarios of it."""
    from amronet.algorithms import ALGORITHMS
    from amronet.algorithms.self_spreading.controller import SelfSpreading
    from amronet.scenario import load_scenario

    @ALGORITHMS.register("test-undeclared")
    class Undeclared(SelfSpreading):
        scenario_defaults = {"routers.count": 7}  # noqa: RUF012

    try:
        scenario = load_scenario({"map": "obstacles-6x6", "base_stations": [{"x": 0.5, "y": 0.5}],
                                  "algorithm": {"name": "test-undeclared"}})
        assert scenario.routers.count == 7 and scenario.algorithm_params() == SelfSpreading.Params()
    finally:
        del ALGORITHMS._items["test-undeclared"]
