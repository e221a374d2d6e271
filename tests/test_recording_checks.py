"""Forged and damaged recordings (issue #45): refused before anything is decoded, in one line naming the array.

Each case takes a small valid recording, alters one of its arrays (or the file's bytes) and checks that the
library raises :class:`~amronet.errors.RecordingError` naming the file and the array, and that ``snapshot``,
``animate`` and ``replay`` refuse it with one line and exit status 2, writing nothing.
"""

from __future__ import annotations

import json
import tracemalloc
import zipfile
from collections.abc import Callable
from pathlib import Path

import numpy as np
import pytest

from amronet import limits
from amronet.cli import main
from amronet.errors import AmronetError, RecordingError
from amronet.outputs.recording import Recording, load_recording

Arrays = dict[str, np.ndarray]


@pytest.fixture(scope="module")
def base(tmp_path_factory) -> Arrays:
    """The arrays of a valid recording: 5 frames of 31 robots on a 300 x 300 map."""
    out = tmp_path_factory.mktemp("rec") / "run"
    argv = ["run", "--preset", "self-spreading-6x6", "--set", "sim.time_limit=2", "--seed", "2", "-q", "--out",
            str(out), "--record", "--record-every", "5"]
    assert main(argv) == 0
    with np.load(out / "recording.npz") as data:
        return {k: data[k] for k in data.files}


def _linked(a: Arrays) -> Arrays:
    """``a`` with stored links (as a medium other than the unit disk writes them): robots 0-1 in every frame."""
    frames = len(a["steps"])
    return {**a, "link_offsets": np.arange(frames + 1, dtype=np.int64),
            "link_pairs": np.tile(np.array([[0, 1]], np.uint16), (frames, 1))}


def _set(a: Arrays, key: str, f: Callable[[np.ndarray], np.ndarray]) -> Arrays:
    return {**a, key: f(a[key].copy())}


def _meta(a: Arrays, **change) -> Arrays:
    return {**a, "meta": np.array(json.dumps({**json.loads(str(a["meta"])), **change}))}


def _budget(a: Arrays, **change) -> Arrays:
    """``a`` as a log-distance run with these link budget fields (numbers its radio could not have had)."""
    meta = json.loads(str(a["meta"]))
    return _meta(a, medium="log-distance", budget={**meta["budget"], **change})


def _poke(arr: np.ndarray, index: tuple, value) -> np.ndarray:
    arr[index] = value
    return arr


# (case, how the arrays are altered, the array the refusal must name)
CASES: list[tuple[str, Callable[[Arrays], Arrays], str]] = [
    ("quantum-nan", lambda a: {**a, "xy_quantum": np.array(np.nan)}, "xy_quantum"),
    ("quantum-inf", lambda a: {**a, "xy_quantum": np.array(np.inf)}, "xy_quantum"),
    ("quantum-zero", lambda a: {**a, "xy_quantum": np.array(0.0)}, "xy_quantum"),
    ("quantum-negative", lambda a: {**a, "xy_quantum": np.array(-1e-4)}, "xy_quantum"),
    ("quantum-beyond-the-map", lambda a: {**a, "xy_quantum": np.array(5.0)}, "xy_quantum"),
    ("quantum-not-a-scalar", lambda a: {**a, "xy_quantum": np.zeros(3)}, "xy_quantum"),
    ("resolution-zero", lambda a: {**a, "map_resolution": np.array(0.0)}, "map_resolution"),
    ("resolution-negative", lambda a: {**a, "map_resolution": np.array(-0.02)}, "map_resolution"),
    ("resolution-nan", lambda a: {**a, "map_resolution": np.array(np.nan)}, "map_resolution"),
    ("status-wrong-shape", lambda a: {**a, "status": np.zeros((len(a["steps"]), 200_000), np.uint8)}, "status"),
    ("status-flat", lambda a: _set(a, "status", np.ravel), "status"),
    ("status-wrong-dtype", lambda a: _set(a, "status", lambda s: s.astype(np.float32)), "status"),
    ("positions-wrong-shape", lambda a: _set(a, "xy_delta", lambda d: d[..., 0]), "xy_delta"),
    ("positions-wrong-dtype", lambda a: _set(a, "xy_delta", lambda d: d.astype(np.float64)), "xy_delta"),
    ("positions-fewer-frames", lambda a: _set(a, "xy_delta", lambda d: d[:-1]), "xy_delta"),
    ("positions-missing", lambda a: {k: v for k, v in a.items() if k != "xy_delta"}, "xy_delta"),
    ("kind-more-robots", lambda a: _set(a, "kind", lambda k: np.concatenate([k, k[:3]])), "kind"),
    ("n-more-robots-than-stored", lambda a: _set(a, "n", lambda n: n + 5), "n"),
    ("n-fewer-frames", lambda a: _set(a, "n", lambda n: n[:-1]), "n"),
    ("state-unknown-code", lambda a: _set(a, "state", lambda s: _poke(s, (0, 0), 200)), "state"),
    ("kind-unknown-code", lambda a: _set(a, "kind", lambda k: _poke(k, 0, 9)), "kind"),
    ("status-below-none", lambda a: _set(a, "status", lambda s: _poke(s.astype(np.int16), (0, 0), -7)),
     "status"),
    ("t-nan", lambda a: _set(a, "t", lambda t: _poke(t, 1, np.nan)), "t"),
    ("steps-backwards", lambda a: _set(a, "steps", lambda s: s[::-1].copy()), "steps"),
    ("reachable-short", lambda a: _set(a, "reachable", lambda r: r[:-10]), "reachable"),
    ("map-unknown-cell", lambda a: _set(a, "map_cells", lambda c: _poke(c, (0, 0), 7)), "map_cells"),
    ("map-origin-inf", lambda a: _set(a, "map_origin", lambda o: _poke(o, 0, np.inf)), "map_origin"),
    ("xy-origin-off-the-map", lambda a: _set(a, "xy_origin", lambda o: o + 1e6), "xy_origin"),
    ("links-offsets-disagree", lambda a: _set(_linked(a), "link_offsets", lambda o: o * 2), "link_offsets"),
    ("links-beyond-robots", lambda a: _set(_linked(a), "link_pairs", lambda p: p + 100), "link_pairs"),
    ("links-half-stored", lambda a: {k: v for k, v in _linked(a).items() if k != "link_pairs"}, "link_pairs"),
    ("meta-r_c-negative", lambda a: _meta(a, r_c=-1.0), "meta.r_c"),
    ("meta-budget-exponent-tiny", lambda a: _budget(a, exponent=1e-300), "meta.budget.exponent"),
    ("meta-budget-shadowing-huge", lambda a: _budget(a, shadowing_db=1e6), "meta.budget.shadowing_db"),
    ("meta-budget-clip-huge", lambda a: _budget(a, shadowing_clip=1e6, shadowing_db=5.0), "meta.budget"),
]

# the cases the command line is run on: the ones of the issue, and one of each kind of damage
CLI_CASES = ["quantum-nan", "quantum-inf", "quantum-zero", "quantum-negative", "resolution-zero",
             "resolution-negative", "resolution-nan", "status-wrong-shape", "status-wrong-dtype",
             "positions-wrong-shape", "positions-wrong-dtype", "n-more-robots-than-stored", "links-offsets-disagree",
             "meta-r_c-negative", "meta-budget-exponent-tiny", "meta-budget-shadowing-huge"]


def _write(arrays: Arrays, folder: Path) -> Path:
    folder.mkdir(parents=True)
    np.savez_compressed(folder / "recording.npz", **arrays)
    return folder


def _truncated(folder: Path, base: Arrays) -> str:
    path = _write(base, folder) / "recording.npz"
    path.write_bytes(path.read_bytes()[: path.stat().st_size // 2])
    return "file"


def _garbled(folder: Path, base: Arrays) -> str:
    """Overwrite bytes in the middle of the compressed data of ``map_cells``."""
    path = _write(base, folder) / "recording.npz"
    blob = bytearray(path.read_bytes())
    with zipfile.ZipFile(path) as archive:
        info = archive.getinfo("map_cells.npy")
    local = blob[info.header_offset: info.header_offset + 30]
    start = info.header_offset + 30 + int.from_bytes(local[26:28], "little") + int.from_bytes(local[28:30], "little")
    middle = start + info.compress_size // 2
    blob[middle: middle + 24] = bytes(range(7, 31))
    path.write_bytes(bytes(blob))
    return "map_cells"


FILE_CASES = {"truncated": _truncated, "garbled": _garbled}


def _one_line(exc: BaseException, path: Path, field: str) -> str:
    text = str(exc)
    assert len(text.splitlines()) == 1, text
    assert str(path) in text and field.split(".")[-1] in text, text
    return text


@pytest.fixture
def roomy(monkeypatch):
    monkeypatch.setattr(limits, "available_memory", lambda: 64 * 2**30)


@pytest.mark.parametrize(("case", "alter", "field"), CASES, ids=[c[0] for c in CASES])
def test_a_forged_recording_is_refused_naming_the_array(case, alter, field, base, tmp_path, roomy):
    folder = _write(alter(base), tmp_path / "run")
    with pytest.raises(RecordingError) as info:
        load_recording(folder)
    assert info.value.field == field
    _one_line(info.value, folder / "recording.npz", field)
    with pytest.raises(RecordingError) as info:  # the arrays as a library caller hands them over
        Recording.from_arrays(alter(base), where="forged.npz")
    assert info.value.field == field


@pytest.mark.parametrize("case", sorted(FILE_CASES))
def test_a_truncated_or_garbled_file_is_refused(case, base, tmp_path, roomy):
    field = FILE_CASES[case](tmp_path / "run", base)
    with pytest.raises(RecordingError) as info:
        load_recording(tmp_path / "run")
    assert info.value.field == field
    _one_line(info.value, tmp_path / "run" / "recording.npz", field)


def test_the_valid_recordings_still_load(base, tmp_path, roomy):
    rec = load_recording(_write(base, tmp_path / "plain"))
    assert rec.frames == len(base["steps"]) and rec.link_offsets is None
    rec = load_recording(_write(_linked(base), tmp_path / "linked"))
    np.testing.assert_array_equal(rec.links(2), [[0, 1]])


@pytest.mark.parametrize("command", ["snapshot", "animate", "replay"])
@pytest.mark.parametrize("case", [*CLI_CASES, *sorted(FILE_CASES)])
def test_every_command_refuses_a_forged_recording_in_one_line(command, case, base, tmp_path, capsys, roomy):
    folder = tmp_path / "run"
    if case in FILE_CASES:
        field = FILE_CASES[case](folder, base)
    else:
        _, alter, field = next(c for c in CASES if c[0] == case)
        _write(alter(base), folder)
    out = tmp_path / {"snapshot": "s.png", "animate": "a.gif", "replay": "r.html"}[command]
    assert main([command, str(folder), "--out", str(out), "-q"]) == 2
    captured = capsys.readouterr()
    err = captured.err.strip()
    assert err.startswith("amronet: error: ") and "Traceback" not in err
    _one_line(AmronetError(err), folder / "recording.npz", field)
    assert not out.exists()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["run"]


def _stream_npz(path: Path, arrays: Arrays, big: str, shape: tuple[int, ...]) -> None:
    """Write ``arrays`` with array ``big`` replaced by zeros (uint8) of ``shape``, streamed, never in memory."""
    with zipfile.ZipFile(path, "w", zipfile.ZIP_DEFLATED) as archive:
        for key, arr in arrays.items():
            if key != big:
                with archive.open(f"{key}.npy", "w") as fp:
                    np.lib.format.write_array(fp, arr, allow_pickle=False)
                continue
            with archive.open(f"{key}.npy", "w", force_zip64=True) as fp:
                np.lib.format.write_array_header_1_0(fp, {"descr": "|u1", "fortran_order": False, "shape": shape})
                chunk = bytes(2**20)
                total = int(np.prod(shape))
                for start in range(0, total, len(chunk)):
                    fp.write(chunk[: min(len(chunk), total - start)])


def test_a_wrong_shaped_status_is_refused_before_its_data_is_read(base, tmp_path, roomy):
    """The issue's case: a small file whose status unpacks to far more than the robots; no memory is spent on it."""
    path = tmp_path / "recording.npz"
    _stream_npz(path, base, "status", (len(base["steps"]), 8_000_000))  # 40 MB of zeros in about 40 KB
    assert path.stat().st_size < 2**20
    tracemalloc.start()
    try:
        with pytest.raises(RecordingError, match=r"'status' .*shape \(5, 8000000\)") as info:
            load_recording(path)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert info.value.field == "status"
    assert peak < 8 * 2**20


def test_a_map_that_unpacks_to_more_than_the_memory_is_refused(base, tmp_path, monkeypatch):
    """A consistent recording whose (compressible) map would take more memory to draw than there is."""
    side = 2000
    huge = {**base, "map_cells": np.zeros((side, side), np.int8),
            "reachable": np.packbits(np.ones(side * side, bool))}
    folder = _write(huge, tmp_path / "run")
    assert (folder / "recording.npz").stat().st_size < 2**20
    monkeypatch.setattr(limits, "available_memory", lambda: 64 * 2**20)
    with pytest.raises(AmronetError, match=r"a 2000 x 2000 map.* would need about .* but 64 MiB are available"):
        load_recording(folder)

