"""Checks of a recording before anything in it is decoded: its arrays' headers, their layout, the memory, the values.

Every reader of ``recording.npz`` goes through here: ``load_recording`` (so ``amronet snapshot``, ``animate``,
``replay``) calls :func:`read_recording_arrays`, and ``Recording.from_arrays`` :func:`read_meta` and :func:`validate`:

1. the header (shape and type) of each array of the format, read alone: refused when it claims more bytes than
   the file holds or than its compressed size can expand to;
2. the layout (:func:`check_layout`): every array is there with its type, and the shapes agree on ``F`` frames,
   ``N`` robots, ``L`` stored links and a map of ``R x C`` cells (``reachable`` packed in ``ceil(R C / 8)`` bytes);
   when the arrays disagree, the odd one out is named;
3. the memory: the arrays, the decoded positions and the map's rasters for the pictures must fit in the memory
   available (:mod:`amronet.limits`), so a small file that unpacks to gigabytes is refused before it is unpacked;
4. the data, array by array (a truncated or garbled array is named);
5. the values (:func:`check_values`): finite, positive scales (``xy_quantum``, ``map_resolution``; ``r_c`` in
   :func:`read_meta`), a position grid on the map, codes of known roles, states and map cells, robot counts within
   the arrays, stored links between robots present, steps and times that do not go back.

Each refusal is a :class:`~amronet.errors.RecordingError`: one line naming the file, the array and what is wrong.
Arrays of other names are neither read nor counted.
"""

from __future__ import annotations

import dataclasses
import json
import math
import zipfile
import zlib
from collections import Counter
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np

from amronet import limits
from amronet.engine.propagation import RADIO_BOUNDS, LinkBudget
from amronet.engine.radio import MEDIA
from amronet.engine.robots import ROLE_NAMES, STATE_NAMES
from amronet.errors import AmronetError, RecordingError
from amronet.outputs.recording_codec import FORMAT, Q_MAX
from amronet.scenario import MAX_RANGE_M
from amronet.world.loading import MAX_COORDINATE_M
from amronet.world.occupancy import FREE, OCCUPIED, UNKNOWN

__all__ = ["DECODE_BYTES_PER_POSITION", "check_layout", "check_values", "read_budget", "read_meta",
           "read_recording_arrays", "validate"]

Layout = Mapping[str, tuple[tuple[int, ...], np.dtype]]
"""Array name → (shape, dtype), from the arrays' headers or from the arrays themselves."""

_U8, _I8, _U16, _I16, _I32 = (np.dtype(t) for t in (np.uint8, np.int8, np.uint16, np.int16, np.int32))
# name → (shape, in symbols F, N, L, R, C, B = ceil(R C / 8), F+1, or numbers; the dtypes allowed)
_SPEC: dict[str, tuple[tuple[str | int, ...], str | tuple[np.dtype, ...]]] = {
    "meta": ((), "text"),
    "steps": (("F",), "integers"),
    "t": (("F",), "floating-point numbers"),
    "n": (("F",), "integers"),
    "kind": (("N",), (_U8,)),
    "xy_origin": ((2,), "floating-point numbers"),
    "xy_quantum": ((), "floating-point numbers"),
    "xy_delta": (("F", "N", 2), (_U16,)),
    "state": (("F", "N"), (_U8,)),
    "status": (("F", "N"), (_U8, _I16)),
    "map_cells": (("R", "C"), (_I8,)),
    "map_resolution": ((), "floating-point numbers"),
    "map_origin": ((2,), "floating-point numbers"),
    "reachable": (("B",), (_U8,)),
    "link_offsets": (("F+1",), "integers"),
    "link_pairs": (("L", 2), (_U16, _I32)),
}
_LINKS = ("link_offsets", "link_pairs")  # optional, together
_WORDS = {"F": "frames", "N": "robots", "L": "links", "R": "map rows", "C": "map columns", "B": "map cells / 8",
          "F+1": "frames + 1"}
# which arrays' dimensions say how many frames and robots there are (the majority wins; the odd one is named)
_FRAMES = (("steps", 0), ("t", 0), ("n", 0), ("xy_delta", 0), ("state", 0), ("status", 0))
_ROBOTS = (("kind", 0), ("xy_delta", 1), ("state", 1), ("status", 1))
_META_KEYS = ("algorithm", "map", "seed", "r_c")  # what the pictures read from ``meta``
_BUDGET_FIELDS = tuple(f.name for f in dataclasses.fields(LinkBudget))
_RESOLUTION_RANGE = (1e-6, 1e6)  # metres per cell, as map files (amronet.world.loading)
_DEFLATE_MAX_RATIO = 1100
"""Deflate packs at most 1 032 bytes into one: a member claiming to expand more is forged."""
DECODE_BYTES_PER_POSITION = 24
"""Decoding one stored coordinate of ``xy_delta`` (uint16): its running sum (2 B), the float64 products (2 x 8 B)
and the float32 result (4 B)."""


# -- meta ------------------------------------------------------------------------------------------------------
def read_meta(data: Mapping[str, Any], where: str) -> dict[str, Any]:
    """The recording's ``meta`` (a JSON object of the format ``amronet-recording/1``), with ``r_c`` checked.

    Raises:
        RecordingError: ``meta`` is missing, not a JSON object, of another format, lacks a key the pictures read,
            or its ``r_c`` is not a positive finite range.
    """
    if "meta" not in data:
        raise RecordingError(where, "meta", "array 'meta' is missing")
    try:
        meta = json.loads(str(data["meta"]))
    except (ValueError, TypeError):
        raise RecordingError(where, "meta", "its meta is not valid JSON") from None
    if not isinstance(meta, dict):
        raise RecordingError(where, "meta", f"its meta is a JSON {type(meta).__name__}, not an object")
    if meta.get("format") != FORMAT:
        raise RecordingError(where, "meta.format", f"its meta's format {meta.get('format')!r:.40} is not {FORMAT}")
    missing = [k for k in _META_KEYS if k not in meta]
    if missing:
        raise RecordingError(where, f"meta.{missing[0]}", f"its meta lacks {missing[0]!r}")
    r_c = meta["r_c"]
    if isinstance(r_c, bool) or not isinstance(r_c, int | float) or not 0 < r_c <= MAX_RANGE_M:  # NaN fails too
        raise RecordingError(where, "meta.r_c", f"its meta's r_c {r_c!r:.40} is not a range in metres in "
                                                f"(0, {MAX_RANGE_M:g}]")
    return meta


def read_budget(meta: Mapping[str, Any], where: str) -> LinkBudget:
    """The link budget recorded in ``meta`` (with its medium and seed checked, to rebuild the medium).

    Raises:
        RecordingError: The budget, the medium's name or the seed is malformed.
    """
    raw = meta["budget"]
    if not isinstance(raw, dict) or "r_c" not in raw:
        raise RecordingError(where, "meta.budget", "its meta's 'budget' is not a link budget")
    values: dict[str, float] = {}
    for key, value in raw.items():
        if key not in _BUDGET_FIELDS:
            raise RecordingError(where, "meta.budget", f"its meta's budget has an unknown field {key!r}")
        if isinstance(value, bool) or not isinstance(value, int | float) or not -1e300 < value < 1e300:
            raise RecordingError(where, f"meta.budget.{key}", f"its meta's budget.{key} is not a finite number")
        values[key] = float(value)
    budget = LinkBudget(**values)
    if not 0 < budget.r_c <= MAX_RANGE_M or not 0 <= budget.shadowing_clip <= 10.0:  # runs clip at 3 sigma
        raise RecordingError(where, "meta.budget", "its meta's budget is out of range")
    for key in ("tx_dbm", "pl0_db", "exponent", "wall_db", "shadowing_db", "shadowing_corr_m"):  # as a scenario's
        if RADIO_BOUNDS["path_loss_exponent" if key == "exponent" else key].problem(getattr(budget, key)):
            raise RecordingError(where, f"meta.budget.{key}", f"its meta's budget.{key} is out of range")
    if not isinstance(meta.get("medium"), str) or meta["medium"] not in MEDIA:
        raise RecordingError(where, "meta.medium", f"its meta's medium {meta.get('medium')!r:.40} is not a radio model "
                                                   f"of this amronet: {', '.join(sorted(MEDIA))}")
    seed = meta.get("seed")
    if isinstance(seed, bool) or not isinstance(seed, int) or seed < 0:
        raise RecordingError(where, "meta.seed", f"its meta's seed {seed!r:.40} is not a whole number >= 0")
    return budget


# -- layout ----------------------------------------------------------------------------------------------------
def _dtype_ok(dtype: np.dtype, allowed: str | tuple[np.dtype, ...]) -> bool:
    if allowed == "text":
        return dtype.kind == "U"
    if allowed == "integers":
        return dtype.kind in "iu"
    if allowed == "floating-point numbers":
        return dtype.kind == "f"
    return any(dtype.kind == a.kind and dtype.itemsize == a.itemsize for a in allowed)


def _majority(layout: Layout, dims: tuple[tuple[str, int], ...]) -> int:
    """The size most of ``dims`` (array, axis) give (ties: the first array's)."""
    sizes = [layout[name][0][axis] for name, axis in dims if name in layout and len(layout[name][0]) > axis]
    return Counter(sizes).most_common(1)[0][0] if sizes else 0


def check_layout(layout: Layout, where: str) -> None:
    """Check that the arrays of a recording are all there, of their types, and that their shapes agree.

    Args:
        layout: Array name → (shape, dtype), of every array of the recording (others are ignored).
        where: The file, as messages name it.

    Raises:
        RecordingError: An array is missing, of another type, or of a shape that disagrees with the others (the
            message names it, its shape and the shape it must have).
    """
    if (_LINKS[0] in layout) != (_LINKS[1] in layout):
        absent = _LINKS[0] if _LINKS[0] not in layout else _LINKS[1]
        raise RecordingError(where, absent, f"array {absent!r} is missing: stored links need both arrays")
    for name, (_, allowed) in _SPEC.items():
        if name not in layout:
            if name in _LINKS:
                continue
            raise RecordingError(where, name, f"array {name!r} is missing")
        dtype = layout[name][1]
        if not _dtype_ok(dtype, allowed):
            want = allowed if isinstance(allowed, str) else " or ".join(a.name for a in allowed)
            raise RecordingError(where, name, f"array {name!r} holds {dtype}, not {want}")
    size: dict[str | int, int] = {"F": _majority(layout, _FRAMES), "N": _majority(layout, _ROBOTS)}
    size["F+1"] = size["F"] + 1
    cells = layout["map_cells"][0]
    if len(cells) == 2:
        size["R"], size["C"] = cells
        size["B"] = -(-cells[0] * cells[1] // 8)
    if "link_pairs" in layout and len(layout["link_pairs"][0]) >= 1:
        size["L"] = layout["link_pairs"][0][0]
    for name, (dims, _) in _SPEC.items():
        if name not in layout:
            continue
        want = tuple(size.get(d, -1) if isinstance(d, str) else d for d in dims)
        shape = tuple(layout[name][0])
        if shape != want:
            words = " x ".join(_WORDS[d] if isinstance(d, str) else str(d) for d in dims) or "a single number"
            shown = f"{want} ({words})" if -1 not in want else f"({words})"
            raise RecordingError(where, name, f"array {name!r} has shape {shape}, not {shown}")
    if size["F"] == 0:
        raise RecordingError(where, "steps", "array 'steps' holds no frame")


def _decoding(layout: Layout) -> int:
    """Bytes to decode a recording of this layout and draw it, besides its arrays."""
    positions, cells = math.prod(layout["xy_delta"][0]), math.prod(layout["map_cells"][0])
    return positions * DECODE_BYTES_PER_POSITION + cells * limits.BYTES_PER_MAP_CELL


# -- reading a file --------------------------------------------------------------------------------------------
def _header(archive: zipfile.ZipFile, info: zipfile.ZipInfo, name: str, where: str) -> tuple[tuple[int, ...], np.dtype]:
    """The shape and dtype of one array, read from its header alone, checked against the bytes the file holds."""
    try:
        with archive.open(info) as fp:
            version = np.lib.format.read_magic(fp)
            read = np.lib.format.read_array_header_1_0 if version == (1, 0) else np.lib.format.read_array_header_2_0
            shape, _, dtype = read(fp)
            header = fp.tell()
    except (ValueError, OSError, EOFError, zipfile.BadZipFile, zlib.error, NotImplementedError) as exc:
        raise RecordingError(where, name, f"array {name!r}: {type(exc).__name__} reading its header") from None
    nbytes = math.prod(shape) * dtype.itemsize
    packed = info.compress_size * _DEFLATE_MAX_RATIO + 4096 if info.compress_type != zipfile.ZIP_STORED else None
    if nbytes > info.file_size - header or (packed is not None and info.file_size > packed):
        stored = limits.format_bytes(info.compress_size)
        raise RecordingError(where, name, f"array {name!r} claims shape {tuple(shape)} of {dtype}, "
                                          f"{limits.format_bytes(nbytes)}, in {stored} of file")
    return tuple(shape), dtype


def read_recording_arrays(path: Path) -> dict[str, np.ndarray]:
    """The arrays of ``recording.npz``, each read only after the headers, the layout and the memory are checked.

    Raises:
        RecordingError: The file is not a zip archive of arrays (or is truncated), an array's header is damaged or
            claims more than the file holds, the layout is wrong (:func:`check_layout`), or an array's data is
            truncated or garbled.
        AmronetError: The arrays, their decoding and the map's rasters need more memory than is available.
    """
    where = str(path)
    try:
        archive = zipfile.ZipFile(path)
    except (zipfile.BadZipFile, OSError, EOFError, ValueError) as exc:
        raise RecordingError(where, "file", f"the file is not a recording: not a zip archive of arrays, or truncated "
                                            f"({type(exc).__name__})") from None
    with archive:
        infos = {info.filename.removesuffix(".npy"): info for info in archive.infolist()}
        infos = {name: info for name, info in infos.items() if name in _SPEC}
        layout = {name: _header(archive, info, name, where) for name, info in infos.items()}
        check_layout(layout, where)
        total = sum(math.prod(shape) * dtype.itemsize for shape, dtype in layout.values())
        rows, cols = layout["map_cells"][0]
        limits.check_memory(total + _decoding(layout), "",
                            f"reading {where} (a {rows} x {cols} map, {limits.format_bytes(total)} of arrays)",
                            "read it on a machine with more memory, or record fewer frames (--record-every)",
                            error=AmronetError)
        arrays: dict[str, np.ndarray] = {}
        for name, info in infos.items():
            try:
                with archive.open(info) as fp:
                    arrays[name] = np.lib.format.read_array(fp, allow_pickle=False)
            except (ValueError, OSError, EOFError, zipfile.BadZipFile, zlib.error) as exc:
                raise RecordingError(where, name, f"array {name!r} is truncated or garbled ({type(exc).__name__} "
                                                  "reading its data)") from None
    return arrays


# -- values ----------------------------------------------------------------------------------------------------
def _first(bad: np.ndarray) -> tuple[int, ...]:
    """Index of the first ``True`` of ``bad`` (without listing them all)."""
    return tuple(int(i) for i in np.unravel_index(int(np.argmax(bad)), bad.shape))


def _check_map(a: Mapping[str, np.ndarray], where: str) -> tuple[float, np.ndarray, np.ndarray]:
    """Check ``map_resolution``, ``map_origin``, ``map_cells``; return resolution, lower-left corner and size."""
    res = float(a["map_resolution"])
    low, high = _RESOLUTION_RANGE
    if not (math.isfinite(res) and low <= res <= high):
        raise RecordingError(where, "map_resolution", f"array 'map_resolution' is {res!r}: it must be a finite number "
                                                      f"of metres per cell in [{low:g}, {high:g}]")
    origin = np.asarray(a["map_origin"], dtype=np.float64)
    cells = a["map_cells"]
    size = np.array(cells.shape[::-1], dtype=np.float64) * res
    if not (np.isfinite(origin).all() and np.abs(origin).max() <= MAX_COORDINATE_M
            and np.abs(origin + size).max() <= MAX_COORDINATE_M):
        raise RecordingError(where, "map_origin", f"array 'map_origin' is {origin.tolist()}: the map must lie within "
                                                  f"{MAX_COORDINATE_M:g} m of the world origin")
    bad = (cells != FREE) & (cells != OCCUPIED) & (cells != UNKNOWN)
    if bad.any():
        r, c = _first(bad)
        raise RecordingError(where, "map_cells", f"array 'map_cells' holds {int(cells[r, c])} at row {r}, column "
                                                 f"{c}; a cell is {FREE}, {OCCUPIED} or {UNKNOWN}")
    return res, origin, size


def _check_positions(a: Mapping[str, np.ndarray], where: str, res: float, corner: np.ndarray, size: np.ndarray) -> None:
    """Check that the position grid (``xy_origin``, ``xy_quantum``) is the map's, as the recorder lays it."""
    quantum = float(a["xy_quantum"])
    if not (math.isfinite(quantum) and quantum > 0):
        raise RecordingError(where, "xy_quantum", f"array 'xy_quantum' is {quantum!r}: it must be a finite number of "
                                                  "metres > 0")
    longer = float(size.max())
    if quantum * Q_MAX > longer * (1 + 1e-9):
        raise RecordingError(where, "xy_quantum", f"array 'xy_quantum' is {quantum:g} m: {Q_MAX} of it span "
                                                  f"{quantum * Q_MAX:g} m, beyond the map's longer side ({longer:g} m)")
    origin = np.asarray(a["xy_origin"], dtype=np.float64)
    if not (np.isfinite(origin).all() and np.abs(origin - corner).max() <= res):
        raise RecordingError(where, "xy_origin", f"array 'xy_origin' is {origin.tolist()}: it must be the map's "
                                                 f"lower-left corner {corner.tolist()}")


def _check_frames(a: Mapping[str, np.ndarray], where: str) -> None:
    """Check ``steps``, ``t`` and ``n`` against each other and the robots stored."""
    steps, t, n = (np.asarray(a[k]) for k in ("steps", "t", "n"))
    if (steps < 0).any() or (np.diff(steps) < 0).any():
        f = _first((steps < 0) | np.r_[False, np.diff(steps) < 0])[0]
        raise RecordingError(where, "steps", f"array 'steps' goes back or below 0 at frame {f} ({int(steps[f])})")
    if not np.isfinite(t).all() or (np.diff(t) < 0).any():
        f = _first(~np.isfinite(t) | np.r_[False, np.diff(t) < 0])[0]
        raise RecordingError(where, "t", f"array 't' is {float(t[f])!r} at frame {f}: times are finite and never go "
                                         "back")
    robots = a["kind"].shape[0]
    if (n < 0).any() or (n > robots).any():
        f = _first((n < 0) | (n > robots))[0]
        raise RecordingError(where, "n", f"array 'n' says frame {f} has {int(n[f])} robots, but the arrays hold "
                                         f"{robots}")
    if (np.diff(n) < 0).any() or int(n.max()) != robots:
        raise RecordingError(where, "n", f"array 'n' ({int(n.min())} to {int(n.max())} robots, "
                                         f"{'shrinking' if (np.diff(n) < 0).any() else 'growing'}) disagrees with the "
                                         f"{robots} robots of the arrays; robots are added, never removed")


def _check_codes(a: Mapping[str, np.ndarray], where: str) -> None:
    """Check the role, state and status codes."""
    kind, state, status = a["kind"], a["state"], a["status"]
    if (kind >= len(ROLE_NAMES)).any():
        i = _first(kind >= len(ROLE_NAMES))[0]
        raise RecordingError(where, "kind", f"array 'kind' holds {int(kind[i])} for robot {i}; roles are 0 to "
                                            f"{len(ROLE_NAMES) - 1} ({', '.join(ROLE_NAMES)})")
    if (state >= len(STATE_NAMES)).any():
        f, i = _first(state >= len(STATE_NAMES))
        raise RecordingError(where, "state", f"array 'state' holds {int(state[f, i])} for robot {i} in frame {f}; "
                                             f"states are 0 to {len(STATE_NAMES) - 1}")
    if status.dtype.kind == "i" and (status < -1).any():
        f, i = _first(status < -1)
        raise RecordingError(where, "status", f"array 'status' holds {int(status[f, i])} for robot {i} in frame {f}; "
                                              "a base station's id is >= 0, or -1 for none")


def _check_links(a: Mapping[str, np.ndarray], where: str) -> None:
    """Check stored links: offsets from 0 to their count, pairs between robots present in their frame."""
    if "link_offsets" not in a:
        return
    offsets, pairs = np.asarray(a["link_offsets"]).astype(np.int64), np.asarray(a["link_pairs"])
    if offsets[0] != 0 or (np.diff(offsets) < 0).any() or offsets[-1] != len(pairs):
        raise RecordingError(where, "link_offsets", f"array 'link_offsets' runs from {int(offsets[0])} to "
                                                    f"{int(offsets[-1])}, not from 0 up to the {len(pairs)} stored "
                                                    "links")
    present = np.repeat(np.asarray(a["n"], dtype=np.int64), np.diff(offsets))
    bad = (pairs < 0).any(axis=1) | (pairs >= present[:, None]).any(axis=1)
    if bad.any():
        k = _first(bad)[0]
        f = int(np.searchsorted(offsets, k, side="right")) - 1
        raise RecordingError(where, "link_pairs", f"array 'link_pairs' links robots {pairs[k].tolist()} in frame "
                                                  f"{f}, which has {int(present[k])} robots")


def check_values(arrays: Mapping[str, np.ndarray], where: str) -> None:
    """Check the values of a recording whose layout is right (:func:`check_layout`): scales, bounds, codes, counts.

    Raises:
        RecordingError: One line naming the array and what is wrong with its values.
    """
    _check_positions(arrays, where, *_check_map(arrays, where))
    _check_frames(arrays, where)
    _check_codes(arrays, where)
    _check_links(arrays, where)


def validate(arrays: Mapping[str, np.ndarray], where: str) -> None:
    """Check a recording's arrays (layout, then values) before anything is decoded from them.

    Args:
        arrays: The arrays of ``recording.npz`` (others than the format's are ignored).
        where: The file, as messages name it.

    Raises:
        RecordingError: One line naming the file, the array and what is wrong.
    """
    layout = {}
    for name in _SPEC:
        if name in arrays:
            arr = np.asarray(arrays[name])
            layout[name] = (arr.shape, arr.dtype)
    check_layout(layout, where)
    check_values({name: np.asarray(arrays[name]) for name in layout}, where)
