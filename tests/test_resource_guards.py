"""Resource guards (issue #18): inputs that would eat the machine or run for ever are refused before allocating.

Every case is one line and exit status 2 on the command line (a typed error in the library), and nothing is
written. Memory is checked against ``amronet.limits.available_memory``, which the tests monkeypatch so that they
do not depend on the machine; absurd work is refused unless acknowledged (``--force``, ``force=True``), which the
tests check with the thresholds monkeypatched low.
"""

from __future__ import annotations

import io
import json
import struct
import subprocess
import sys
import time
import warnings
import zipfile
import zlib
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

from amronet import limits
from amronet.cli import main
from amronet.errors import AmronetError, MapError, ScenarioError
from amronet.outputs.recording import load_recording
from amronet.patterns import as_area, lattice, place
from amronet.scenario import list_presets, load_scenario
from amronet.sim import Simulation
from amronet.sim.bench import run_bench
from amronet.sim.guard import check_scenario
from amronet.sweeps.spec import sweep_from_spec
from amronet.world.builtin import resolve_map
from amronet.world.loading import load_map_yaml

GiB = 1024**3


@pytest.fixture
def memory(monkeypatch):
    """Set the memory the guard sees: ``memory(bytes)``."""

    def set_available(n: int | None) -> None:
        monkeypatch.setattr(limits, "available_memory", lambda: n)

    set_available(64 * GiB)  # a roomy machine unless a test says otherwise
    return set_available


def cli(capsys, *argv: str) -> tuple[int, str]:
    code = main(list(argv))
    err = capsys.readouterr().err
    return code, err


def refused(code: int, err: str, field: str) -> str:
    """Assert a one-line refusal naming ``field``; return the line."""
    assert code == 2, err
    lines = err.strip().splitlines()
    assert len(lines) == 1, err
    assert lines[0].startswith(f"amronet: error: {field}"), lines[0]
    return lines[0]


def run_args(out: Path, *sets: str, preset: str = "self-spreading-6x6") -> list[str]:
    args = ["run", "--preset", preset, "--seed", "1", "--out", str(out), "-q", "--no-snapshot"]
    for s in sets:
        args += ["--set", s]
    return args


# -- runs: robots, steps, memory ---------------------------------------------------------------------------------
@pytest.mark.parametrize("count", ["10000000", "1000000000000"])
def test_huge_router_counts_are_refused_before_anything_is_built(tmp_path, capsys, memory, count):
    out = tmp_path / "out"
    t0 = time.perf_counter()
    line = refused(*cli(capsys, *run_args(out, f"routers.count={count}")), "routers.count")
    assert time.perf_counter() - t0 < 5
    assert "m² of floor for their bodies" in line and "base_stations[0]" in line
    assert not out.exists()


def test_a_million_agents_per_base_are_refused(tmp_path, capsys, memory):
    out = tmp_path / "out"
    line = refused(*cli(capsys, *run_args(out, "agents.per_base=1000000", preset="agent-assisted-office")),
                   "agents.per_base")
    assert "1000000 agents" in line
    assert not out.exists()


def test_robots_that_do_not_fit_in_memory_are_refused_saying_how_much(tmp_path, capsys, memory):
    memory(100 * 1024**2)
    out = tmp_path / "out"
    line = refused(*cli(capsys, *run_args(out, "routers.count=5000", "radio.r_c=20.0",
                                          "base_stations.0.region=[10.0, 10.0]")), "routers.count")
    assert "would need about 1.5" in line and "GiB of memory, but 100 MiB are available" in line
    assert not out.exists()


def test_a_map_that_does_not_fit_in_memory_with_its_run_is_refused(capsys, memory):
    sc = load_scenario("self-spreading-6x6")
    omap = resolve_map(sc.map)
    memory(1024**2)  # the 300 x 300 cells of open-6x6 need about 5.5 MiB in a run
    with pytest.raises(ScenarioError) as info:
        Simulation(sc, 1, omap=omap)
    assert info.value.field == "map"
    assert "a map of 300 x 300 cells" in info.value.message and "coarser map" in info.value.message


@pytest.mark.parametrize(("key", "value", "field"), [
    ("sim.dt", "0.000000001", "sim.dt"),
    ("sim.time_limit", "1000000000000", "sim.time_limit"),
])
def test_billions_of_steps_are_refused_without_force(tmp_path, capsys, memory, key, value, field):
    out = tmp_path / "out"
    line = refused(*cli(capsys, *run_args(out, f"{key}={value}")), field)
    assert "steps would take absurdly long" in line and "10,000,000" in line and "--force" in line
    assert not out.exists()


def test_uncountable_steps_are_refused_even_with_force(tmp_path, capsys, memory):
    out = tmp_path / "out"
    line = refused(*cli(capsys, *run_args(out, "sim.dt=1.0e-300", "sim.time_limit=1.0e+300"), "--force"), "sim.dt")
    assert "not a countable number of steps" in line


def test_force_lets_a_long_run_start(tmp_path, capsys, memory, monkeypatch):
    monkeypatch.setattr(limits, "MAX_STEPS", 50)  # time_limit 10 s / dt 0.1 s = 100 steps: "absurdly long"
    out = tmp_path / "out"
    refused(*cli(capsys, *run_args(out, "sim.time_limit=10")), "sim.time_limit")
    assert not out.exists()
    code, err = cli(capsys, *run_args(out, "sim.time_limit=10"), "--force")
    assert code == 0, err
    assert json.loads((out / "summary.json").read_text())["sim_time_s"] <= 10


def test_force_in_the_library_and_robot_steps(memory, monkeypatch):
    sc = load_scenario("self-spreading-6x6", {"sim.time_limit": 5.0})
    monkeypatch.setattr(limits, "MAX_ROBOT_STEPS", 1000)  # 31 robots x 50 steps
    with pytest.raises(ScenarioError) as info:
        Simulation(sc, 1)
    assert info.value.field == "routers.count" and "31 robots x 50 steps = 1,550 robot-steps" in info.value.message
    sim = Simulation(sc, 1, force=True)
    sim.step()
    assert sim.steps == 1


def test_every_preset_passes_the_guard(memory):
    for name in list_presets():
        check_scenario(load_scenario(name))


# -- maps ----------------------------------------------------------------------------------------------------------
def _png_claiming(path: Path, width: int, height: int) -> None:
    """A PNG whose header claims ``width x height`` grey pixels (its data is a few bytes: never decoded here)."""
    buf = io.BytesIO()
    Image.new("L", (4, 4), 254).save(buf, "PNG")
    data = bytearray(buf.getvalue())
    ihdr = data.index(b"IHDR")
    data[ihdr + 4: ihdr + 12] = struct.pack(">II", width, height)
    data[ihdr + 17: ihdr + 21] = struct.pack(">I", zlib.crc32(bytes(data[ihdr: ihdr + 17])))
    path.write_bytes(bytes(data))


def _map_yaml(folder: Path, image: str, origin: str = "[0.0, 0.0, 0.0]", resolution: str = "0.05") -> Path:
    path = folder / "m.yaml"
    path.write_text(f"image: {image}\nresolution: {resolution}\norigin: {origin}\nnegate: 0\n"
                    "occupied_thresh: 0.65\nfree_thresh: 0.196\n")
    return path


def test_a_huge_map_image_is_refused_from_its_header(tmp_path, capsys, memory):
    memory(2 * GiB)
    _png_claiming(tmp_path / "big.png", 13000, 13000)
    yaml_path = _map_yaml(tmp_path, "big.png")
    with pytest.raises(MapError) as info:
        load_map_yaml(yaml_path)
    assert info.value.field == "map.image"
    assert "(13000 x 13000 pixels, L) would need about 3.78 GiB of memory, but 2 GiB are available" in str(info.value)
    out = tmp_path / "out"
    refused(*cli(capsys, *run_args(out, f"map={yaml_path}", "base_stations.0.x=3.0", "base_stations.0.y=3.0")),
            "map.image")
    assert not out.exists()


def test_a_map_far_from_the_origin_is_one_line_without_warnings(tmp_path, capsys):
    Image.new("L", (100, 100), 254).save(tmp_path / "small.pgm")
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        with pytest.raises(MapError) as info:
            load_map_yaml(_map_yaml(tmp_path, "small.pgm", origin="[1.0e+308, 0.0, 0.0]"))
        assert info.value.field == "map.origin"
        out = tmp_path / "out"
        refused(*cli(capsys, *run_args(out, f"map={tmp_path / 'm.yaml'}")), "map.origin")
        with pytest.raises(MapError, match="far edge in x"):
            load_map_yaml(_map_yaml(tmp_path, "small.pgm", origin="[999999999.0, 0.0, 0.0]", resolution="1000.0"))
        with pytest.raises(MapError) as info:
            load_map_yaml(_map_yaml(tmp_path, "small.pgm", resolution="1.0e-300"))
        assert info.value.field == "map.resolution"


# -- sweeps --------------------------------------------------------------------------------------------------------
def _sweep(grid: dict, seeds: int = 1) -> dict:
    return {"name": "g", "base": "self-spreading-6x6", "overrides": {"sim.time_limit": 1.0}, "grid": grid,
            "seeds": seeds}


def test_a_grid_of_a_million_points_is_refused_before_it_is_expanded(memory):
    grid = {"radio.r_c": [0.5 + i / 1000 for i in range(1000)], "routers.count": list(range(1, 1001))}
    t0 = time.perf_counter()
    with pytest.raises(ScenarioError) as info:
        sweep_from_spec(_sweep(grid))
    assert info.value.field == "grid"
    assert "1000 x 1000 = 1,000,000 points would take absurdly long" in info.value.message
    memory(GiB)
    with pytest.raises(ScenarioError) as info:
        sweep_from_spec(_sweep(grid), force=True)
    assert info.value.field == "grid" and "would need about 8.58 GiB of memory, but 1 GiB" in info.value.message
    assert time.perf_counter() - t0 < 3


def test_force_lets_a_large_sweep_expand(memory, monkeypatch, capsys, tmp_path):
    monkeypatch.setattr(limits, "MAX_SWEEP_POINTS", 3)
    monkeypatch.setattr(limits, "MAX_SWEEP_RUNS", 10)
    spec = _sweep({"radio.r_c": [0.8, 1.0, 1.2], "routers.count": [5, 10]})
    with pytest.raises(ScenarioError, match="6 points would take absurdly long"):
        sweep_from_spec(spec, check_start=False)
    assert len(sweep_from_spec(spec, check_start=False, force=True).points) == 6
    with pytest.raises(ScenarioError) as info:
        sweep_from_spec({**spec, "grid": {"radio.r_c": [0.8]}, "seeds": 11}, check_start=False)
    assert info.value.field == "seeds" and "1 points x 11 seeds = 11 runs" in info.value.message
    path = tmp_path / "sweep.yaml"
    path.write_text(json.dumps(spec))
    refused(*cli(capsys, "sweep", str(path), "--store", str(tmp_path / "s.sqlite")), "grid")
    assert not (tmp_path / "s.sqlite").exists()


def test_a_sweep_point_whose_runs_are_absurdly_long_is_refused(memory):
    with pytest.raises(ScenarioError) as info:
        sweep_from_spec(_sweep({"sim.time_limit": [10.0, 1e9]}), check_start=False, force=True)
    assert info.value.field == "grid.sim.time_limit"
    assert "(at point 1: sim.time_limit = 1000000000.0)" in info.value.message
    assert "amronet run --force" in info.value.message


# -- recordings ----------------------------------------------------------------------------------------------------
@pytest.fixture(scope="module")
def recorded(tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("rec") / "run"
    assert main([*run_args(out, "sim.time_limit=2"), "--record"]) == 0
    return out


def _forge(src: Path, dst: Path, key: str, shape: tuple[int, ...]) -> None:
    """Copy a recording, giving array ``key`` a header that claims ``shape`` (its data stays as it was)."""
    with zipfile.ZipFile(src) as zin, zipfile.ZipFile(dst, "w", zipfile.ZIP_DEFLATED) as zout:
        for info in zin.infolist():
            data = zin.read(info.filename)
            if info.filename == f"{key}.npy":
                fp = io.BytesIO(data)
                np.lib.format.read_magic(fp)
                _, _, dtype = np.lib.format.read_array_header_1_0(fp)
                head = io.BytesIO()
                np.lib.format.write_array_header_1_0(head, {"descr": np.lib.format.dtype_to_descr(dtype),
                                                            "fortran_order": False, "shape": shape})
                data = head.getvalue() + data[fp.tell():]
            zout.writestr(info.filename, data)


def test_a_recording_whose_header_claims_terabytes_is_refused(recorded, tmp_path, capsys, memory):
    folder = tmp_path / "forged"
    folder.mkdir()
    for f in recorded.iterdir():
        if f.is_file() and f.name != "recording.npz":
            (folder / f.name).write_bytes(f.read_bytes())
    _forge(recorded / "recording.npz", folder / "recording.npz", "xy_delta", (11, 180_000_000_000, 2))
    with pytest.raises(AmronetError, match=r"array 'xy_delta' claims shape \(11, 180000000000, 2\) of uint16, 7.2 TiB"):
        load_recording(folder)
    for command, name in (("replay", "r.html"), ("animate", "r.gif"), ("snapshot", "r.png")):
        code, err = cli(capsys, command, str(folder), "--out", str(tmp_path / name))
        line = refused(code, err, str(folder / "recording.npz"))
        assert "is damaged" in line
        assert not (tmp_path / name).exists()


def test_a_recording_that_does_not_fit_in_memory_is_refused(recorded, memory):
    assert load_recording(recorded).frames >= 2
    memory(4096)
    with pytest.raises(AmronetError, match=r"reading .*recording.npz \(.* of arrays\) would need about .* but 4 KiB"):
        load_recording(recorded)


# -- patterns ------------------------------------------------------------------------------------------------------
@pytest.mark.parametrize(("args", "size"), [(["--area", "1000000x1000000", "--r", "4"], "TiB"),
                                            (["--r", "0.00001"], "PiB")])
def test_patterns_with_a_huge_area_or_a_tiny_r_are_refused(capsys, memory, args, size):
    memory(16 * GiB)
    line = refused(*cli(capsys, "patterns", *args), "--area/--r")
    assert f"{size} of memory, but 16 GiB are available; use a larger r or a smaller area" in line


def test_patterns_library_guards_and_force(memory, monkeypatch):
    with pytest.raises(AmronetError, match=r"^r: the square pattern"):
        place("square", (1e6, 1e6), 4.0)
    with pytest.raises(AmronetError, match=r"^r: the square lattice"):
        lattice("square", 1e-5, 1000.0, 1000.0)
    monkeypatch.setattr(limits, "MAX_PATTERN_WORK", 1000)
    area = as_area((8.0, 8.0), r=4.0)
    with pytest.raises(AmronetError, match="would take absurdly long"):
        place("square", area, 4.0)
    assert place("square", area, 4.0, force=True).count > 0


# -- bench ---------------------------------------------------------------------------------------------------------
def test_bench_with_ten_million_robots_is_refused(capsys, memory):
    memory(8 * GiB)
    line = refused(*cli(capsys, "bench", "--robots", "10000000", "--steps", "1"), "--robots")
    assert "10000000 robots would need about 26.6 GiB of memory, but 8 GiB are available" in line
    memory(64 * GiB)
    line = refused(*cli(capsys, "bench", "--robots", "10000000", "--steps", "500"), "--robots")
    assert "5,010,000,000 robot-steps would take absurdly long" in line and "--force" in line


def test_bench_force_runs_past_the_guard(memory, monkeypatch):
    monkeypatch.setattr(limits, "MAX_ROBOT_STEPS", 10)
    with pytest.raises(AmronetError, match=r"^--robots: 20 robots x 3 steps"):
        run_bench(robots=20, steps=2, map_name="open-6x6")
    assert run_bench(robots=20, steps=2, map_name="open-6x6", force=True)["steps"] == 2


# -- overflows -----------------------------------------------------------------------------------------------------
def test_dssa_with_an_astronomical_range_is_one_line(tmp_path, capsys):
    out = tmp_path / "out"
    line = refused(*cli(capsys, *run_args(out, "radio.r_c=1.0e+300", preset="dssa-6x6")), "radio.r_c")
    assert "longest range amronet models, 100000 m" in line
    for area in ("1.0e-300", "1.0e+300"):
        line = refused(*cli(capsys, *run_args(out, f"algorithm.params.field_area={area}", preset="dssa-6x6")),
                       "algorithm.params.field_area")
        assert "expected density" in line
    assert not out.exists()


# -- the machine ---------------------------------------------------------------------------------------------------
def test_available_memory_respects_the_address_space_limit():
    code = ("import resource; resource.setrlimit(resource.RLIMIT_AS, (3 * 1024**3, resource.getrlimit("
            "resource.RLIMIT_AS)[1])); from amronet.limits import available_memory; print(available_memory())")
    text = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert 0 <= int(text) < 3 * 1024**3
    assert limits.format_bytes(7.2 * 1024**4) == "7.2 TiB" and limits.format_bytes(512) == "512 B"
