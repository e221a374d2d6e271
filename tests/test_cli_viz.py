"""End-to-end tests of ``amronet run --record``, ``snapshot``, ``animate`` and ``replay``, including bad input."""

from __future__ import annotations

import base64
import json
import re
import shutil
import sys
import zlib

import numpy as np
import pytest
from PIL import Image

from amronet.cli import main

TINY = ["--preset", "self-spreading-6x6", "--set", "sim.time_limit=20", "--seed", "2", "-q"]


@pytest.fixture(scope="module")
def recorded(tmp_path_factory):
    out = tmp_path_factory.mktemp("runs") / "a"
    assert main(["run", *TINY, "--out", str(out), "--record", "--record-every", "5"]) == 0
    return out


@pytest.fixture(scope="module")
def plain(tmp_path_factory):
    out = tmp_path_factory.mktemp("runs") / "b"
    assert main(["run", *TINY, "--out", str(out)]) == 0
    return out


def _error(capsys) -> str:
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and err.startswith("amronet: error: ")
    return err


def test_run_record_writes_the_recording_with_the_other_files(recorded, plain):
    names = sorted(p.name for p in recorded.iterdir())
    assert names == [".amronet-manifest.json", "network.json", "recording.npz", "snapshot.png", "summary.json",
                     "timeseries.csv"]
    with np.load(recorded / "recording.npz") as data:
        assert data["steps"].tolist() == list(range(0, 201, 5))
    assert not (plain / "recording.npz").exists()
    # recording changes nothing else
    assert (recorded / "network.json").read_bytes() == (plain / "network.json").read_bytes()


def test_snapshot_png_svg_and_time(recorded, plain, tmp_path, capsys):
    assert main(["snapshot", str(recorded), "--out", str(tmp_path / "end.png"), "--dpi", "50", "-q"]) == 0
    assert main(["snapshot", str(recorded), "--out", str(tmp_path / "t5.svg"), "--time", "5", "-q"]) == 0
    assert main(["snapshot", str(plain), "--out", str(tmp_path / "net.png"), "--dpi", "50", "-q"]) == 0
    end = np.asarray(Image.open(tmp_path / "end.png").convert("RGB"), dtype=int)
    net = np.asarray(Image.open(tmp_path / "net.png").convert("RGB"), dtype=int)
    assert end.shape == net.shape and end.std() > 0
    assert np.abs(end - net).mean() < 3  # the same run's last frame, from the recording or from network.json
    assert "t = 5 s" in (tmp_path / "t5.svg").read_text()


@pytest.mark.parametrize("run", ["recorded", "plain"])
def test_svg_snapshots_of_a_run_are_byte_identical(run, request, tmp_path):
    folder = request.getfixturevalue(run)
    for name in ("a.svg", "b.svg"):
        assert main(["snapshot", str(folder), "--out", str(tmp_path / name), "-q"]) == 0
    assert (tmp_path / "a.svg").read_bytes() == (tmp_path / "b.svg").read_bytes()


def test_animate_gif(recorded, tmp_path):
    out = tmp_path / "run.gif"
    assert main(["animate", str(recorded), "--out", str(out), "--max-frames", "5", "--dpi", "40", "-q"]) == 0
    assert Image.open(out).n_frames == 5
    assert not [p for p in tmp_path.iterdir() if p.name.startswith(".")]  # no temporary file left


def test_replay_page_is_self_contained(recorded, tmp_path):
    out = tmp_path / "replay.html"
    assert main(["replay", str(recorded), "--out", str(out), "-q"]) == 0
    page = out.read_text()
    assert not re.search(r"""(src|href)\s*=\s*["']?(https?:)?//""", page)  # nothing fetched
    assert "fetch(" not in page and "import(" not in page
    header = json.loads(re.search(r'id="amronet-header">(.*?)</script>', page, re.S).group(1))
    assert header["frames"] == 41 and header["robots"] == 31 and header["r_c"] == 1.0
    payload = re.search(r'id="amronet-payload">(.*?)</script>', page, re.S).group(1)
    raw = zlib.decompress(base64.b64decode(payload))
    xy = header["arrays"]["xy_delta"]
    assert xy["dtype"] == "uint16" and xy["length"] == 41 * 31 * 2
    assert len(raw) >= xy["offset"] + 2 * xy["length"]
    assert len(header["timeseries"]["t"]) == 21


def test_replay_reports_the_frames_the_page_holds(recorded, tmp_path, capsys):
    out = tmp_path / "replay.html"
    assert main(["replay", str(recorded), "--out", str(out), "--every", "3", "--max-frames", "5"]) == 0
    assert capsys.readouterr().out.startswith("replay of 5 frames of 41 recorded, 31 robots")
    header = json.loads(re.search(r'id="amronet-header">(.*?)</script>', out.read_text(), re.S).group(1))
    assert header["frames"] == 5


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["replay", "{plain}", "--out", "{tmp}/r.html"], "has no recording.npz: run it again with --record"),
        (["animate", "{plain}", "--out", "{tmp}/r.gif"], "has no recording.npz: run it again with --record"),
        (["replay", "{tmp}/nowhere", "--out", "{tmp}/r.html"], "is not a folder"),
        (["replay", "{recorded}", "--out", "{tmp}/r.txt"], "--out: .* must end in .html"),
        (["animate", "{recorded}", "--out", "{tmp}/r.avi"], "--out: .* must end in .gif or .mp4"),
        (["animate", "{recorded}", "--out", "{tmp}/r.gif", "--fps", "0"], "--fps"),
        (["animate", "{recorded}", "--out", "{tmp}/r.gif", "--fps", "1e9"],
         r"--fps: 1e\+09 must be between 0.01 and 50 frames per second for GIF, e.g. 10$"),
        (["animate", "{recorded}", "--out", "{tmp}/r.gif", "--fps", "0.001"], "--fps: 0.001 must be between"),
        (["animate", "{recorded}", "--out", "{tmp}/r.gif", "--fps", "nan"], "--fps: nan must be between"),
        (["animate", "{recorded}", "--out", "{tmp}/r.gif", "--max-frames", "0"], "--max-frames: 0 must be >= 2"),
        (["replay", "{recorded}", "--out", "{tmp}/r.html", "--every", "-1"], "--every: -1 must be >= 1"),
        (["replay", "{recorded}", "--out", "{tmp}/r.html", "--max-frames", "1"], "--max-frames: 1 must be >= 2"),
        (["animate", "{recorded}", "--out", "{tmp}/r.gif", "--every", "0"], "--every"),
        (["snapshot", "{recorded}", "--out", "{tmp}/r.jpg"], "--out: .* must end in .png or .svg"),
        (["snapshot", "{plain}", "--out", "{tmp}/r.png", "--time", "3"], "--time: .* run it again with --record"),
        (["snapshot", "{recorded}", "--out", "{tmp}/r.png", "--time", "-1"], "--time"),
        (["snapshot", "{recorded}", "--out", "{tmp}/r.png", "--dpi", "0"], "--dpi"),
        (["run", *TINY, "--out", "{tmp}/x", "--record-every", "0"], "--record-every"),
    ],
)
def test_bad_input_is_one_line(argv, message, recorded, plain, tmp_path, capsys):
    argv = [a.format(plain=plain, recorded=recorded, tmp=tmp_path) for a in argv]
    assert main(argv) == 2
    assert re.search(message, _error(capsys))
    assert [p.name for p in tmp_path.iterdir()] == []


def _damaged_recording(recorded, folder, meta: str):
    folder.mkdir()
    with np.load(recorded / "recording.npz") as data:
        arrays = {k: data[k] for k in data.files}
    np.savez_compressed(folder / "recording.npz", **{**arrays, "meta": np.array(meta)})
    return folder


@pytest.mark.parametrize("command", ["snapshot", "animate", "replay"])
@pytest.mark.parametrize(("meta", "why"), [("{not json", "its meta is not valid JSON"),
                                           ("[1, 2]", "its meta is a JSON list, not an object"),
                                           ('{"format": "amronet-recording/1"}', "its meta lacks 'algorithm'")])
def test_a_damaged_recording_is_one_line_naming_the_file(command, meta, why, recorded, tmp_path, capsys):
    folder = _damaged_recording(recorded, tmp_path / "run", meta)
    out = tmp_path / {"snapshot": "s.png", "animate": "a.gif", "replay": "r.html"}[command]
    assert main([command, str(folder), "--out", str(out), "-q"]) == 2
    err = _error(capsys)
    assert f"{folder / 'recording.npz'} is damaged or was not written by amronet run --record ({why})" in err
    assert not out.exists()


@pytest.mark.parametrize(
    ("name", "content", "why"),
    [
        ("network.json", lambda d: {k: v for k, v in d.items() if k != "nodes"}, "no 'nodes'"),
        ("network.json", lambda d: {**d, "nodes": [{"x": 1}]}, "a node or r_c is malformed: no 'y'"),
        ("network.json", lambda d: {**d, "nodes": "many"}, "'nodes' is not a list"),
        ("summary.json", lambda d: [d], "a JSON list, not an object"),
        ("summary.json", lambda d: {k: v for k, v in d.items() if k != "seed"}, "no 'seed'"),
        ("summary.json", None, "not valid JSON: Expecting value at line 1"),
    ],
)
def test_a_damaged_run_folder_is_one_line_naming_the_file(name, content, why, plain, tmp_path, capsys):
    folder = tmp_path / "run"
    shutil.copytree(plain, folder)
    path = folder / name
    path.write_text("not json" if content is None else json.dumps(content(json.loads(path.read_text()))))
    out = tmp_path / "s.png"
    assert main(["snapshot", str(folder), "--out", str(out), "-q"]) == 2
    err = _error(capsys)
    assert f"{path} is damaged or was not written by amronet run ({why}); run it again" in err
    assert not out.exists()


def test_replay_ignores_a_summary_that_is_not_an_object(recorded, tmp_path):
    folder = tmp_path / "run"
    shutil.copytree(recorded, folder)
    (folder / "summary.json").write_text('["stop_reason", "coverage"]')
    (folder / "timeseries.csv").write_text("t,coverage,connected_coverage\n0.0,0.1\n")
    assert main(["replay", str(folder), "--out", str(tmp_path / "r.html"), "-q"]) == 0
    header = json.loads(re.search(r'id="amronet-header">(.*?)</script>', (tmp_path / "r.html").read_text(),
                                  re.S).group(1))
    assert header["summary"] == {} and len(header["timeseries"]["t"]) == header["frames"]


def test_mp4_without_encoder(recorded, tmp_path, capsys, monkeypatch):
    monkeypatch.setitem(sys.modules, "imageio_ffmpeg", None)
    assert main(["animate", str(recorded), "--out", str(tmp_path / "r.mp4")]) == 2
    assert "needs an encoder: pip install 'amronet[video]'" in _error(capsys)
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["animate", "--out", "{tmp}/r.avi"], "--out: .* must end in .gif or .mp4"),
        (["animate", "--out", "{tmp}/r.gif", "--fps", "0"], "--fps: 0 must be between"),
        (["animate", "--out", "{tmp}/r.mp4", "--fps", "200"], "--fps: 200 must be between 0.01 and 120"),
        (["animate", "--out", "{tmp}/r.gif", "--every", "0"], "--every: 0 must be >= 1"),
        (["animate", "--out", "{tmp}/r.gif", "--max-frames", "1"], "--max-frames: 1 must be >= 2"),
        (["animate", "--out", "{tmp}/r.gif", "--dpi", "0"], "--dpi"),
        (["replay", "--out", "{tmp}/r.txt"], "--out: .* must end in .html"),
        (["replay", "--out", "{tmp}/r.html", "--every", "0"], "--every: 0 must be >= 1"),
        (["replay", "--out", "{tmp}/r.html", "--max-frames", "1"], "--max-frames: 1 must be >= 2"),
    ],
)
def test_cheap_options_are_checked_before_the_recording_is_loaded(argv, message, tmp_path, capsys, monkeypatch):
    import amronet.outputs.recording

    def never(*args, **kwargs):
        raise AssertionError("the recording was loaded before the options were checked")

    monkeypatch.setattr(amronet.outputs.recording, "load_recording", never)
    folder = tmp_path / "run"
    folder.mkdir()
    (folder / "recording.npz").write_bytes(b"not a recording")
    out = tmp_path / "out"
    out.mkdir()
    argv = [argv[0], str(folder), *(a.format(tmp=out) for a in argv[1:])]
    assert main(argv) == 2
    assert re.search(message, _error(capsys))
    assert list(out.iterdir()) == []
