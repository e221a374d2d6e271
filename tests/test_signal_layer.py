"""The signal layer (issue #14): ``amronet radio-map``, ``snapshot/animate/replay --layer signal``, and recordings
that rebuild their radio medium (walls, shadowing) from their meta."""

from __future__ import annotations

import dataclasses
import io
import json
import os
import re
import shutil
from pathlib import Path

import numpy as np
import pytest

from amronet.cli import main
from amronet.engine.coverage import CoverageArea
from amronet.engine.radio import MultiWall, UnitDisk
from amronet.engine.robots import ROLE_NAMES, STATE_NAMES, Role
from amronet.errors import AmronetError
from amronet.outputs.recording import Recorder, Recording, load_recording
from amronet.scenario import load_scenario
from amronet.sim import Simulation
from amronet.world.builtin import resolve_map
from amronet.world.occupancy import OCCUPIED

PNG = b"\x89PNG\r\n\x1a\n"
FAST = ["--preset", "self-spreading-obstacles-6x6", "--set", "sim.time_limit=5", "--seed", "2", "-q"]


def _one_error_line(capsys) -> str:
    err = capsys.readouterr().err
    lines = err.strip().splitlines()
    assert len(lines) == 1, err
    assert lines[0].startswith("amronet: error: ")
    return lines[0]


def _header(page: bytes) -> dict:
    text = page.decode("utf-8")
    found = re.search(r'<script type="application/json" id="amronet-header">(.*?)</script>', text, re.S)
    assert found is not None
    return json.loads(found.group(1).replace("<\\/", "</"))


def _load(blob: bytes) -> Recording:
    with np.load(io.BytesIO(blob)) as data:
        return Recording.from_arrays({k: data[k] for k in data.files})


def _arrays(blob: bytes) -> dict[str, np.ndarray]:
    with np.load(io.BytesIO(blob)) as data:
        return {k: data[k] for k in data.files}


# -- amronet radio-map ---------------------------------------------------------------------------------------------
def test_radio_map_draws_autolab_under_multi_wall(tmp_path, capsys):
    out = tmp_path / "signal.png"
    argv = ["radio-map", "--map", "autolab", "--node", "2.5,10", "--node", "15,5", "--radio", "multi-wall",
            "--r-c", "4", "--seed", "1", "--out", str(out), "--dpi", "60"]
    assert main(argv) == 0
    assert out.read_bytes()[:8] == PNG and out.stat().st_size > 10_000
    said = capsys.readouterr().out
    assert "radio map of 2 nodes on autolab (multi-wall, threshold -32.0 dBm" in said and str(out) in said
    svg = tmp_path / "signal.svg"  # and the same picture as SVG, byte for byte the same each time
    assert main(["radio-map", "--map", "autolab", "--node", "2.5,10", "--radio", "multi-wall", "--set",
                 "radio.wall_db=10", "--out", str(svg), "-q"]) == 0
    first = svg.read_bytes()
    assert b"best RSSI [dBm]" in first and b"usable threshold" in first
    assert main(["radio-map", "--map", "autolab", "--node", "2.5,10", "--radio", "multi-wall", "--set",
                 "radio.wall_db=10", "--out", str(svg), "-q"]) == 0
    assert svg.read_bytes() == first


def _wall_point() -> str:
    omap = resolve_map("autolab")
    rows, cols = np.nonzero(omap.cells == OCCUPIED)
    x, y = omap.cell_centres(rows[len(rows) // 2], cols[len(cols) // 2])
    return f"{x},{y}"


@pytest.mark.parametrize(("extra", "says"), [
    (["--node", "30,10"], "--node: (30, 10) is outside the map autolab"),
    (["--node", "WALL"], "is in a wall or unknown space of autolab"),
    (["--node", "2.5"], "--node: '2.5' is not X,Y"),
    ([], "--node: give at least one node"),
    (["--node", "2.5,10", "--radio", "two-ray"], "radio.model: unknown radio model 'two-ray'"),
    (["--node", "2.5,10", "--set", "radio.sigma=3"], "radio.sigma: unknown key"),
    (["--node", "2.5,10", "--set", "sim.dt=1"], "--set: 'sim.dt' is not a radio field"),
    (["--node", "2.5,10", "--set", "radio.shadowing_db"], "--set: expected KEY=VALUE"),
    (["--node", "2.5,10", "--radio", "log-distance", "--set", "radio.shadowing_db=-2"],
     "radio.shadowing_db: -2 dB is outside [0, 30] dB"),
    (["--node", "2.5,10", "--set", "radio.wall_db=3"], "radio.wall_db: the unit-disk model has no walls"),
    (["--node", "2.5,10", "--r-c", "-1"], "radio.r_c: input should be greater than 0"),
    (["--node", "2.5,10", "--r-c", "wide"], "--r-c: 'wide' is not a number"),
    (["--node", "2.5,10", "--r-c", "2", "--set", "radio.r_c=3"], "radio.r_c and --r-c both give the range"),
    (["--node", "2.5,10", "--seed", "-3"], "--seed: -3 must be a whole number >= 0"),
    (["--node", "2.5,10", "--dpi", "2"], "--dpi: 2 must be a number between 10 and 1200"),
])
def test_radio_map_bad_input_is_one_line_and_writes_nothing(extra, says, tmp_path, capsys):
    out = tmp_path / "signal.png"
    extra = [_wall_point() if a == "WALL" else a for a in extra]
    assert main(["radio-map", "--map", "autolab", *extra, "--out", str(out)]) == 2
    assert says in _one_error_line(capsys)
    assert list(tmp_path.iterdir()) == []


def test_radio_map_refuses_a_bad_map_or_suffix(tmp_path, capsys):
    assert main(["radio-map", "--map", "atlantis", "--node", "1,1", "--out", str(tmp_path / "a.png")]) == 2
    assert "unknown map 'atlantis'" in _one_error_line(capsys)
    assert main(["radio-map", "--map", "autolab", "--node", "2.5,10", "--out", str(tmp_path / "a.gif")]) == 2
    assert "must end in .png or .svg" in _one_error_line(capsys)
    assert list(tmp_path.iterdir()) == []


# -- run folders under multi-wall ----------------------------------------------------------------------------------
@pytest.fixture(scope="module")
def walls_run(tmp_path_factory) -> Path:
    """A short recorded run under the multi-wall radio, and a copy of it without its recording."""
    runs = tmp_path_factory.mktemp("walls")
    assert main(["run", *FAST, "--set", "radio.model=multi-wall", "--out", str(runs / "rec"), "--record"]) == 0
    shutil.copytree(runs / "rec", runs / "plain")
    (runs / "plain" / "recording.npz").unlink()
    return runs


@pytest.fixture(scope="module")
def disk_run(tmp_path_factory) -> Path:
    runs = tmp_path_factory.mktemp("disk")
    assert main(["run", *FAST, "--out", str(runs / "rec"), "--record"]) == 0
    return runs / "rec"


@pytest.mark.parametrize("folder", ["rec", "plain"])
def test_snapshot_signal_layer_of_a_multi_wall_run(walls_run, folder, tmp_path):
    run = walls_run / folder
    for layer in ("signal", "coverage"):
        assert main(["snapshot", str(run), "--out", str(tmp_path / f"{layer}.svg"), "--layer", layer, "-q"]) == 0
    signal, coverage = (tmp_path / "signal.svg").read_bytes(), (tmp_path / "coverage.svg").read_bytes()
    assert b"best RSSI [dBm]" in signal and b"usable threshold" in signal and b"reachable, uncovered" not in signal
    assert b"best RSSI" not in coverage and b"reachable, uncovered" in coverage
    assert main(["snapshot", str(run), "--out", str(tmp_path / "signal.png"), "--layer", "signal", "-q"]) == 0
    assert (tmp_path / "signal.png").read_bytes()[:8] == PNG


def test_signal_snapshots_of_the_recording_and_of_the_network_agree(walls_run):
    """Both rebuild the run's medium: the signal map of the last frame is the same (up to the position grid)."""
    from amronet.sim.assemble import build_medium, build_world

    rec = load_recording(walls_run / "rec")
    summary = json.loads((walls_run / "plain" / "summary.json").read_text())
    sc = load_scenario(summary["scenario"])
    medium = build_medium(sc, build_world(sc).omap, np.random.default_rng(summary["seed"]), packet_loss=False)
    assert dataclasses.asdict(medium.budget) == rec.meta["budget"]
    network = json.loads((walls_run / "plain" / "network.json").read_text())
    xy = np.array([[n["x"], n["y"]] for n in network["nodes"] if n["kind"] != "agent"])
    ours, theirs = rec.signal(rec.frames - 1), medium.signal_dbm(rec.omap, xy)
    both = np.isfinite(ours) & np.isfinite(theirs)
    assert both.mean() > 0.5
    # positions differ by the recording's grid and network.json's rounding: next to a node or a wall's corner a
    # cell may differ more
    assert np.mean(np.abs(ours[both] - theirs[both]) < 0.05) > 0.99


def test_default_snapshot_is_the_picture_of_old(disk_run, tmp_path):
    """Unit disk, default layer: the very picture the coverage tint within r_c gave before the signal layer."""
    from amronet.viz import Nodes, Shading, snapshot_figure
    from amronet.viz.decorations import save_figure
    from amronet.viz.recorded import frame_title

    assert main(["snapshot", str(disk_run), "--out", str(tmp_path / "default.svg"), "-q"]) == 0
    assert main(["snapshot", str(disk_run), "--out", str(tmp_path / "coverage.svg"), "--layer", "coverage",
                 "-q"]) == 0
    rec = load_recording(disk_run)
    f = rec.frames - 1
    fr = rec.frame(f)
    old_covered = CoverageArea(rec.omap, rec.reachable).covered_mask(fr["xy"][fr["kind"] != Role.AGENT], rec.r_c)
    np.testing.assert_array_equal(rec.covered(f), old_covered)
    nodes = Nodes(xy=fr["xy"], kind=np.array(ROLE_NAMES)[fr["kind"]], state=np.array(STATE_NAMES)[fr["state"]],
                  status=fr["status"].astype(np.int64), r_c=rec.r_c, links=rec.links(f), trails=rec.trails(f))
    fig = snapshot_figure(rec.omap, nodes, Shading(covered=old_covered, reachable=rec.reachable),
                          title=frame_title(rec, f), dpi=120)
    save_figure(fig, tmp_path / "old.svg", "svg", 120, facecolor="white")
    old = (tmp_path / "old.svg").read_bytes()
    assert (tmp_path / "default.svg").read_bytes() == old
    assert (tmp_path / "coverage.svg").read_bytes() == old


def test_a_bad_layer_is_one_line(disk_run, tmp_path, capsys):
    for command, out in (("snapshot", "a.png"), ("animate", "a.gif"), ("replay", "a.html")):
        assert main([command, str(disk_run), "--out", str(tmp_path / out), "--layer", "heat"]) == 2
        assert "--layer: 'heat' is not one of coverage, signal" in _one_error_line(capsys)
    assert list(tmp_path.iterdir()) == []


def test_animate_and_replay_signal_layer(walls_run, tmp_path):
    run = walls_run / "rec"
    gif = tmp_path / "signal.gif"
    assert main(["animate", str(run), "--out", str(gif), "--layer", "signal", "--max-frames", "3", "-q"]) == 0
    assert gif.read_bytes()[:6] == b"GIF89a"
    assert main(["replay", str(run), "--out", str(tmp_path / "signal.html"), "--layer", "signal", "-q"]) == 0
    assert main(["replay", str(run), "--out", str(tmp_path / "plain.html"), "-q"]) == 0
    header = _header((tmp_path / "signal.html").read_bytes())
    sig = header["signal"]
    assert max(sig["rows"], sig["cols"]) <= 160 and sig["medium"] == "multi-wall"
    assert sig["threshold_dbm"] == pytest.approx(-20.0)
    assert header["arrays"]["signal"]["dtype"] == "uint8"
    assert header["arrays"]["signal"]["length"] == sig["rasters"] * sig["rows"] * sig["cols"]
    assert header["arrays"]["signal_frame"]["length"] == header["frames"]
    # a run under walls always carries the signal, so the uncovered area is not drawn as disks; it opens on coverage
    plain = _header((tmp_path / "plain.html").read_bytes())
    assert plain["signal"]["first"] is False and sig["first"] is True


def test_replay_rasters_hold_the_coverage_of_the_frame(walls_run):
    """A raster cell reaches the threshold code exactly where the coarse grid's signal reaches the threshold."""
    from amronet.viz.replay import signal_rasters
    from amronet.viz.signal import coarse_grid

    rec = load_recording(walls_run / "rec")
    idx = np.arange(rec.frames)
    rasters, frame_raster, header = signal_rasters(rec, idx, max_side=100)
    assert rasters.shape[1:] == (header["rows"], header["cols"]) and max(rasters.shape[1:]) <= 100
    assert len(frame_raster) == rec.frames and frame_raster[-1] == len(rasters) - 1
    grid, _ = coarse_grid(rec.omap, 100)
    signal = rec.signal(rec.frames - 1, grid=grid)
    shown = rasters[-1] > 0
    heard = np.isfinite(signal) & (signal >= header["threshold_dbm"])
    np.testing.assert_array_equal((rasters[-1] >= header["threshold_code"])[shown], heard[shown])


# -- recordings rebuild their medium -------------------------------------------------------------------------------
@pytest.fixture(scope="module")
def walls_sim():
    """A run under multi-wall with shadowing, recorded through the library (to compare with its exact state)."""
    sc = load_scenario("self-spreading-obstacles-6x6", {"sim.time_limit": 5, "radio.model": "multi-wall",
                                                        "radio.shadowing_db": 4.0})
    recorder = Recorder(every=10)
    result = Simulation(sc, 3).run(recorder=recorder)
    return result, _load(result.files()["recording.npz"])


def test_a_multi_wall_recording_rebuilds_its_medium(walls_sim):
    result, rec = walls_sim
    run = result.run
    medium = run.loop.medium
    assert rec.meta["budget"] == dataclasses.asdict(medium.budget) and rec.meta["packet_loss"] is False
    assert isinstance(rec.medium, MultiWall) and rec.medium.budget == medium.budget
    np.testing.assert_array_equal(rec.medium.shadowing.grid, medium.shadowing.grid)  # the run's field
    sw = run.swarm
    xy = sw.xy[sw.role != Role.AGENT]
    np.testing.assert_array_equal(rec.medium.covered_mask(run.world.coverage, xy),
                                  medium.covered_mask(run.world.coverage, xy))
    # the last frame's coverage is the run's (positions on the recording's grid can move a cell or two)
    assert rec.coverage(rec.frames - 1) == pytest.approx(result.summary["coverage"], abs=1e-3)


def test_recordings_without_a_budget_are_read_with_the_unit_disk(walls_sim):
    result, _ = walls_sim
    arrays = _arrays(result.files()["recording.npz"])
    meta = json.loads(str(arrays["meta"]))
    del meta["budget"], meta["packet_loss"]
    old = Recording.from_arrays({**arrays, "meta": np.array(json.dumps(meta))})
    assert old.budget is None and isinstance(old.medium, UnitDisk)
    f = old.frames - 1
    fr = old.frame(f)
    np.testing.assert_array_equal(old.covered(f), CoverageArea(old.omap, old.reachable).covered_mask(
        fr["xy"][fr["kind"] != Role.AGENT], old.r_c))


@pytest.mark.parametrize(("change", "says"), [
    ({"budget": [1, 2]}, "its meta's 'budget' is not a link budget"),
    ({"budget": {"r_c": 1.0, "gain": 3}}, "unknown field 'gain'"),
    ({"budget": {"r_c": "wide"}}, "budget.r_c is not a finite number"),
    ({"budget": {"r_c": -1.0}}, "its meta's budget is out of range"),
    ({"medium": "two-ray"}, "its meta's medium 'two-ray' is not a radio model"),
    ({"seed": -1}, "its meta's seed -1 is not a whole number >= 0"),
])
def test_a_damaged_budget_is_one_line(walls_sim, change, says):
    result, _ = walls_sim
    arrays = _arrays(result.files()["recording.npz"])
    meta = {**json.loads(str(arrays["meta"])), **change}
    with pytest.raises(AmronetError, match=re.escape(says)) as info:
        Recording.from_arrays({**arrays, "meta": np.array(json.dumps(meta))})
    assert "\n" not in str(info.value)


# -- the replay page's signal toggle in a browser ------------------------------------------------------------------
CHROMIUM = os.environ.get("AMRONET_CHROMIUM", "/usr/bin/chromium")


@pytest.mark.skipif(os.environ.get("AMRONET_SKIP_BROWSER") == "1", reason="AMRONET_SKIP_BROWSER=1")
def test_replay_page_toggles_between_signal_and_uncovered(walls_run, tmp_path):
    sync_playwright = pytest.importorskip("playwright.sync_api").sync_playwright
    if not Path(CHROMIUM).exists():
        pytest.fail(f"{CHROMIUM} is missing: make test installs it (apt-get install chromium), "
                    "or set AMRONET_SKIP_BROWSER=1")
    page_file = tmp_path / "signal.html"
    assert main(["replay", str(walls_run / "rec"), "--out", str(page_file), "--layer", "signal", "-q"]) == 0
    with sync_playwright() as pw:
        browser = pw.chromium.launch(executable_path=CHROMIUM, args=["--headless", "--no-sandbox", "--disable-gpu"])
        page = browser.new_page(viewport={"width": 1280, "height": 900})
        problems: list[str] = []
        page.on("pageerror", lambda e: problems.append(str(e)))
        page.on("console", lambda m: problems.append(m.text) if m.type in ("error", "warning") else None)
        page.goto(page_file.as_uri())
        page.wait_for_function("window.amronetReplay && window.amronetReplay.ready && window.amronetReplay.draws > 0",
                               timeout=30_000)
        assert page.locator("#signal-toggle").is_visible()
        layers = page.evaluate("window.amronetReplay.layers")
        assert layers["signal"] and not layers["uncovered"]
        shot = page.locator("#view").screenshot()
        page.locator("#layer-uncovered").check()
        page.wait_for_function("!window.amronetReplay.layers.signal")
        assert not page.locator("#layer-signal").is_checked()
        page.wait_for_timeout(100)
        assert page.locator("#view").screenshot() != shot
        assert "usable threshold" in page.locator("#legend").inner_text()
        assert problems == [] and page.locator("#error").inner_text() == ""
        browser.close()
