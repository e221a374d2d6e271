"""End-to-end tests of the command line (in-process through ``main`` and one real subprocess)."""

import json
import subprocess
import sys
from pathlib import Path

import pytest
from PIL import Image

from amronet.cli import main

FAST = ["--set", "sim.time_limit=15"]


def run_cli(*argv, capsys=None):
    code = main(list(argv))
    out = capsys.readouterr() if capsys else None
    return code, out


def test_run_preset_writes_all_outputs(tmp_path, capsys):
    out = tmp_path / "a"
    code, cap = run_cli("run", "--preset", "self-spreading-6x6", "--seed", "3", "--out", str(out), *FAST,
                        capsys=capsys)
    assert code == 0, cap.err
    assert sorted(p.name for p in out.iterdir()) == [".amronet-manifest.json", "network.json", "snapshot.png",
                                                      "summary.json", "timeseries.csv"]
    s = json.loads((out / "summary.json").read_text())
    for key in ("algorithm", "map", "seed", "r_c", "sim_time_s", "steps", "terminated", "routers_deployed",
                "nodes_total", "coverage", "connected_coverage", "coverage_method", "agents_connected_fraction",
                "wall_time_s"):
        assert key in s
    assert s["seed"] == 3 and s["sim_time_s"] == 15 and s["terminated"] is False
    assert s["nodes_total"] == s["routers_deployed"] + 1
    header = (out / "timeseries.csv").read_text().splitlines()[0]
    assert header == "t,coverage,connected_coverage,routers_deployed,components"
    net = json.loads((out / "network.json").read_text())
    assert net["r_c"] == 1.0 and len(net["nodes"]) == 31
    assert set(net["nodes"][0]) == {"id", "kind", "state", "status", "x", "y"}
    assert Image.open(out / "snapshot.png").size[0] > 300
    assert "coverage" in cap.out


def test_run_scenario_file_with_overrides(tmp_path, capsys):
    sc = tmp_path / "my.yaml"
    sc.write_text("map: open-6x6\nbase_stations: [{x: 0, y: 0}]\nsim: {time_limit: 5}\n")
    code, cap = run_cli("run", str(sc), "--seed", "1", "--out", str(tmp_path / "b"), "--set", "radio.r_c=1.5",
                        "--set", "routers.count=12", "--no-snapshot", capsys=capsys)
    assert code == 0, cap.err
    s = json.loads((tmp_path / "b" / "summary.json").read_text())
    assert s["r_c"] == 1.5 and s["routers_total"] == 12


@pytest.mark.parametrize(
    ("yaml_text", "words"),
    [
        ("map: open-6x6\nbase_stations: [{x: 0, y: 0}]\nradius: 3\n", "radius: unknown key"),
        ("map: open-6x6\nbase_stations: [{x: 0, y: 0}]\nradio: {r_c: -2}\n", "radio.r_c"),
        ("map: open-6x6\nbase_stations: [{x: 0, y: 0}]\nradio: {r_c: .nan}\n", "radio.r_c"),
        ("map: open-6x6\nbase_stations: [{x: 0, y: 0}]\nrouters: {count: many}\n", "routers.count"),
        ("map: open-6x6\nbase_stations: [{x: 0, y: 0}]\nrouters: {robot: {radius: 0.05, max_speed: -1, "
         "sensor_beams: 8, sensor_range: 0.1}}\n", "routers.robot"),
        ("map: open-6x6\nbase_stations: [{x: 40, y: 0}]\n", "base_stations[0]: (40, 0) is outside the map"),
        ("map: open-6x6\nbase_stations: [{x: -2.999, y: 0}]\n", "base_stations[0]: (-2.999, 0) is inside an obstacle"),
        ("map: open-6x6\nbase_stations: [{x: -2.9, y: 0}]\n", "too close for the reference node's body"),
        ("map: nowhere.yaml\nbase_stations: [{x: 0, y: 0}]\n", "map"),
        ("map: [broken\n", "not valid YAML"),
        ("map: open-6x6\nradio: {r_c: 1}\nbase_stations: [{x: 0, y: 0}]\nradio: {r_c: 2}\n",
         "key 'radio' appears twice in"),  # issue #45 (5f)
    ],
)
def test_bad_input_one_line_exit_2_nothing_written(tmp_path, capsys, yaml_text, words):
    sc = tmp_path / "bad.yaml"
    sc.write_text(yaml_text)
    out = tmp_path / "out"
    code, cap = run_cli("run", str(sc), "--out", str(out), capsys=capsys)
    assert code == 2
    lines = cap.err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("amronet: error: ")
    assert words in lines[0], lines[0]
    assert "Traceback" not in cap.err
    assert not out.exists()
    assert list(tmp_path.iterdir()) == [sc]


def test_map_image_missing_or_not_an_image(tmp_path, capsys):
    (tmp_path / "m.yaml").write_text("image: m.png\nresolution: 0.05\norigin: [0, 0, 0]\nnegate: 0\n"
                                     "occupied_thresh: 0.65\nfree_thresh: 0.196\n")
    sc = tmp_path / "s.yaml"
    sc.write_text("map: m.yaml\nbase_stations: [{x: 1, y: 1}]\n")
    code, cap = run_cli("run", str(sc), "--out", str(tmp_path / "o"), capsys=capsys)
    assert code == 2 and "map.image" in cap.err and len(cap.err.strip().splitlines()) == 1
    (tmp_path / "m.png").write_text("this is not a picture")
    code, cap = run_cli("run", str(sc), "--out", str(tmp_path / "o"), capsys=capsys)
    assert code == 2 and "map.image" in cap.err and len(cap.err.strip().splitlines()) == 1
    assert not (tmp_path / "o").exists()


def test_bad_set_and_missing_source(tmp_path, capsys):
    code, cap = run_cli("run", "--preset", "self-spreading-6x6", "--out", str(tmp_path / "o"), "--set",
                        "radio.r_c=0", capsys=capsys)
    assert code == 2 and "radio.r_c" in cap.err
    code, cap = run_cli("run", "--out", str(tmp_path / "o"), capsys=capsys)
    assert code == 2 and "--preset" in cap.err
    code, cap = run_cli("run", "--preset", "no-such", "--out", str(tmp_path / "o"), capsys=capsys)
    assert code == 2 and "presets" in cap.err


def test_maps_list_and_show(tmp_path, capsys):
    code, cap = run_cli("maps", "list", capsys=capsys)
    assert code == 0
    for name in ("open-6x6", "obstacles-6x6", "open-32x32", "office-32x32", "cave", "hospital_section"):
        assert name in cap.out
    code, cap = run_cli("maps", "list", "--json", capsys=capsys)
    assert {m["name"] for m in json.loads(cap.out)} >= {"cave", "depot"}
    code, cap = run_cli("maps", "show", "cave", "--out", str(tmp_path / "cave.png"), capsys=capsys)
    assert code == 0 and Image.open(tmp_path / "cave.png").size[0] > 200
    code, cap = run_cli("maps", "show", "atlantis", "--out", str(tmp_path / "x.png"), capsys=capsys)
    assert code == 2 and "unknown map" in cap.err and not (tmp_path / "x.png").exists()


def test_maps_list_and_show_give_a_map_the_same_size(tmp_path, capsys):
    """One rounding for both: depot's 307 cells of 0.05 m (15.35 m) print as 15.4 in each."""
    listed = run_cli("maps", "list", capsys=capsys)[1].out
    depot = next(line for line in listed.splitlines() if line.startswith("depot "))
    code, cap = run_cli("maps", "show", "depot", "--out", str(tmp_path / "depot.png"), capsys=capsys)
    assert " 30.2 x 15.4 " in depot, depot
    assert code == 0 and cap.out.startswith("depot: 30.2 m x 15.4 m at 0.05 m/cell"), cap.out


def test_bench_json(capsys):
    code, cap = run_cli("bench", "--robots", "200", "--steps", "5", "--map", "cave", "--json", capsys=capsys)
    assert code == 0
    report = json.loads(cap.out)
    assert report["robots"] == 200 and report["robot_steps_per_s"] > 0
    assert report["threads"] == 1  # a small run: one thread (amronet.threads)


def test_run_step_reference_gives_the_same_network(tmp_path, capsys):
    """``--step reference`` (phase by phase) and the default compiled step write the same network, byte for byte."""
    outs = {}
    for step in ("compiled", "reference"):
        code, cap = run_cli("run", "--preset", "self-spreading-6x6", "--out", str(tmp_path / step), "--set",
                            "sim.time_limit=30", "--no-snapshot", "-q", "--step", step, capsys=capsys)
        assert code == 0, cap.err
        outs[step] = (tmp_path / step / "network.json").read_bytes()
    assert outs["compiled"] == outs["reference"]
    code, cap = run_cli("bench", "--robots", "50", "--steps", "3", "--step", "reference", "--json", capsys=capsys)
    assert code == 0 and json.loads(cap.out)["step"] == "reference"
    with pytest.raises(SystemExit) as exc:  # argparse refuses a step it does not know
        run_cli("run", "--preset", "self-spreading-6x6", "--out", str(tmp_path / "x"), "--step", "fast")
    assert exc.value.code == 2 and "--step" in capsys.readouterr().err and not (tmp_path / "x").exists()


def test_console_script_in_a_subprocess(tmp_path):
    exe = Path(sys.executable).with_name("amronet")
    proc = subprocess.run([str(exe), "run", "--preset", "self-spreading-6x6", "--out", str(tmp_path / "p"),
                           "--set", "sim.time_limit=2", "--no-snapshot", "-q"], capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr
    proc = subprocess.run([str(exe), "run", "--preset", "self-spreading-6x6", "--out", str(tmp_path / "q"),
                           "--set", "radio.r_c=-1"], capture_output=True, text=True)
    assert proc.returncode == 2 and proc.stderr.count("\n") == 1


@pytest.mark.parametrize(("argv", "option"), [(["--steps", "-5"], "--steps"), (["--steps", "0"], "--steps"),
                                              (["--robots", "-3"], "--robots"), (["--rc", "nan"], "--rc"),
                                              (["--rc", "0"], "--rc")])
def test_bench_refuses_bad_sizes_in_one_line(argv, option, capsys):
    code, cap = run_cli("bench", "--map", "open-6x6", "--robots", "30", "--steps", "5", *argv, capsys=capsys)
    assert code == 2 and cap.err.startswith(f"amronet: error: {option}: ") and cap.err.count("\n") == 1


@pytest.mark.parametrize("seed", ["-1", str(2**63)])
def test_bench_refuses_a_bad_seed_as_run_does(seed, tmp_path, capsys):
    """Issue #45 (5a): one line, exit 2, the same validation (and words) as ``run``."""
    code, cap = run_cli("bench", "--map", "open-6x6", "--robots", "30", "--steps", "5", "--seed", seed, capsys=capsys)
    assert code == 2 and cap.err.count("\n") == 1 and "Traceback" not in cap.err
    bench_err = cap.err
    code, cap = run_cli("run", "--preset", "self-spreading-6x6", "--out", str(tmp_path / "o"), "--seed", seed,
                        capsys=capsys)
    assert code == 2 and cap.err == bench_err == f"amronet: error: seed: {seed} is not an integer in [0, 2**63 - 1]; " \
                                                 "give e.g. --seed 1\n"


@pytest.mark.parametrize(("value", "words"), [
    ("sim.dt=1e-9", "sim.dt: sim.time_limit 300 s / sim.dt 1e-09 s = 300,000,000,000 steps would take absurdly long"),
    ("radio.r_c=1e300", "radio.r_c: 1e+300 m is beyond the longest range amronet models"),
    ("radio.r_c=.inf", "radio.r_c: input should be a finite number (got inf)"),
    ("radio={r_c: 1, r_c: 2}", "radio: key 'r_c' appears twice in value '{r_c: 1, r_c: 2}'"),
])
def test_set_reads_the_usual_float_notations(value, words, tmp_path, capsys):
    """Issue #45 (5b): ``1e-9`` is a number (here refused for what it is, not as "not a number")."""
    code, cap = run_cli("run", "--preset", "self-spreading-6x6", "--out", str(tmp_path / "o"), "--set", value,
                        capsys=capsys)
    assert code == 2 and cap.err.count("\n") == 1 and cap.err.startswith(f"amronet: error: {words}"), cap.err
    assert not (tmp_path / "o").exists()


def test_bench_refuses_agent_assisted_naming_its_own_option(capsys):
    code, cap = run_cli("bench", "--algorithm", "agent-assisted", "--map", "open-6x6", "--robots", "30", "--steps",
                        "5", capsys=capsys)
    assert code == 2 and cap.err.count("\n") == 1, cap.err
    assert cap.err.startswith("amronet: error: --algorithm: bench times routers that spread by themselves; in "
                              "agent-assisted agents release them"), cap.err


def test_bench_says_a_too_short_radius_as_rc(capsys):
    code, cap = run_cli("bench", "--map", "open-6x6", "--robots", "30", "--steps", "5", "--rc", "0.05", capsys=capsys)
    assert code == 2 and cap.err.count("\n") == 1, cap.err
    assert cap.err.startswith("amronet: error: --rc: 0.05 m is too short: the 'about to lose' band"), cap.err
    assert cap.err.rstrip().endswith("give a larger --rc") and "sim.dt" not in cap.err
