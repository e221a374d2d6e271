"""The replay viewer: one self-contained HTML page that plays a recorded run in any browser.

The page (``replay_template.html`` beside this module: vanilla JavaScript and one canvas, nothing fetched from
anywhere) gets its data embedded: a small JSON header (map extent, ``r_c``, times, robots per frame, the
coverage time series, colours) and one binary payload — the recording's typed arrays (``uint16`` position
deltas, ``uint8`` states, statuses and kinds) concatenated, zlib-compressed and base64-encoded. The page
inflates it with the browser's own ``DecompressionStream`` and integrates the deltas into a ``Float32Array``
of positions, so the page is about as large as ``recording.npz``. Links are recomputed in the page for each
frame from the positions and ``r_c`` with a uniform grid (unit-disk medium) or read from the stored edge list.
With ``layer="signal"`` (``amronet replay --layer signal``) the payload also carries the best signal of every
frame's routers and base nodes, one byte per cell of a grid of at most 160 cells a side (:func:`signal_rasters`),
and the page toggles between it and the uncovered area.

Drawing is batched: one path per colour and marker shape for nodes, one for all links, one per colour for
disks and trails; the uncovered area is the reachable free space with the disks punched out
(``destination-out``) on an off-screen canvas. Hovering uses a uniform grid over the current frame.
"""

from __future__ import annotations

import base64
import csv
import html
import json
import zlib
from importlib import resources
from pathlib import Path
from typing import Any

import numpy as np
from matplotlib import colormaps
from PIL import Image

from amronet.engine.robots import ROLE_NAMES, STATE_NAMES
from amronet.outputs.recording import Recording
from amronet.viz.nodestyle import LINK_THINNING, NO_STATUS, PALETTE
from amronet.viz.recorded import check_layer, pick_frames
from amronet.viz.signal import CMAP, SPAN_DB, coarse_grid, quantise
from amronet.viz.snapshot import MAP_COLOURS, MAP_LUT, map_image
from amronet.world.occupancy import OCCUPIED, UNKNOWN

__all__ = ["SIGNAL_MAX_SIDE", "TEMPLATE", "replay_html", "replay_payload", "signal_rasters"]

TEMPLATE = "replay_template.html"
"""Name of the page template (package data of ``amronet.viz``)."""

SIGNAL_MAX_SIDE = 160
"""The signal layer's rasters have at most this many cells a side (one byte each, per distinct network)."""


def _hex(rgb: Any) -> str:
    r, g, b = (int(round(255 * float(c))) for c in list(rgb)[:3])
    return f"#{r:02x}{g:02x}{b:02x}"


def _png_b64(rgba: np.ndarray) -> str:
    """``uint8`` image ``(rows, cols, 3|4)`` as a base64 PNG, rows as given (row 0 first)."""
    import io

    buf = io.BytesIO()
    Image.fromarray(np.ascontiguousarray(rgba)).save(buf, format="PNG", optimize=True)
    return base64.b64encode(buf.getvalue()).decode("ascii")


def _timeseries(rec: Recording, folder: Path | None, idx: np.ndarray) -> dict[str, list[float]]:
    """Coverage over time: ``timeseries.csv`` of the run folder, else the recording's own frames (raster)."""
    path = folder / "timeseries.csv" if folder is not None else None
    if path is not None and path.is_file():
        try:  # a damaged file is ignored: the recording's own frames give the curve
            with open(path, newline="") as fh:
                rows = list(csv.DictReader(fh))
            return {key: [round(float(r[key]), 6) for r in rows] for key in ("t", "coverage", "connected_coverage")}
        except (KeyError, ValueError, TypeError, csv.Error):
            pass
    cov = [round(rec.coverage(int(f)), 6) for f in idx]
    return {"t": [float(rec.t[f]) for f in idx], "coverage": cov, "connected_coverage": []}


def signal_rasters(rec: Recording, idx: np.ndarray, max_side: int = SIGNAL_MAX_SIDE
                   ) -> tuple[np.ndarray, np.ndarray, dict[str, Any]]:
    """The signal layer of the page: ``uint8`` rasters of the best RSSI of frames ``idx``, one per distinct network.

    The signal of the routers and base nodes is evaluated on a grid of at most ``max_side`` cells a side over the
    map (:func:`~amronet.viz.signal.coarse_grid`) and quantised on the colour scale
    (:func:`~amronet.viz.signal.quantise`, codes 2-255 from the threshold less 30 dB to the threshold plus 30 dB);
    a cell that counts (reachable free space at its centre) but is blank (weaker still) is 1, a cell that does not
    count is 0. Frames whose routers and base nodes stand where they stood in the previous frame share a raster.

    Returns:
        ``(rasters, frame_raster, header)``: the rasters ``(K, rows, cols)`` (row 0 at the bottom), the raster of
        each frame ``(len(idx),)`` and the page header's ``signal`` entry (grid, scale, colour table, walls).
    """
    grid, k = coarse_grid(rec.omap, max_side)
    rows, cols = grid.shape
    counted = rec.omap.free & rec.reachable
    centre_r = np.minimum(np.arange(rows) * k + k // 2, rec.omap.shape[0] - 1)
    centre_c = np.minimum(np.arange(cols) * k + k // 2, rec.omap.shape[1] - 1)
    shown = counted[np.ix_(centre_r, centre_c)]
    threshold = rec.medium.budget.threshold_dbm
    rasters: list[np.ndarray] = []
    frame_raster = np.zeros(len(idx), dtype=np.int32)
    last: bytes | None = None
    for n, f in enumerate(idx):
        key = np.ascontiguousarray(rec.network_xy(int(f))).tobytes()
        if key != last:
            code = quantise(rec.signal(int(f), grid=grid, floor_db=-SPAN_DB), threshold, first=2)
            rasters.append(np.where(shown, np.maximum(code, 1), 0).astype(np.uint8))
            last = key
        frame_raster[n] = len(rasters) - 1
    lut = np.asarray(colormaps[CMAP](np.linspace(0.0, 1.0, 254)) * 255).round().astype(np.uint8)[:, :3]  # codes 2..255
    walls = np.zeros((*rec.omap.shape, 4), dtype=np.uint8)
    for code, colour in ((OCCUPIED, MAP_LUT[1]), (UNKNOWN, MAP_LUT[2])):
        walls[rec.omap.cells == code] = (*colour, 255)
    x0, _, y0, _ = rec.omap.extent
    header = {
        "rows": rows, "cols": cols, "extent": [x0, y0, cols * grid.resolution, rows * grid.resolution],
        "threshold_dbm": threshold, "lo_dbm": threshold - SPAN_DB, "hi_dbm": threshold + SPAN_DB,
        "threshold_code": 2 + 254 // 2, "lut": lut.ravel().tolist(),
        "walls_png": _png_b64(walls), "rasters": len(rasters), "medium": rec.meta.get("medium", "unit-disk"),
    }
    return np.stack(rasters), frame_raster, header


def replay_payload(rec: Recording, idx: np.ndarray,
                   extra: tuple[tuple[str, np.ndarray], ...] = ()) -> tuple[bytes, dict[str, Any]]:
    """The binary payload (uncompressed) of frames ``idx`` and the descriptors of its arrays (``extra`` appended).

    Returns:
        ``(raw, arrays)``: the concatenated arrays, each starting on a 4-byte boundary, and name →
        ``{dtype, offset, length}``.
    """
    n_all = int(rec.n[idx].max())
    q = np.cumsum(rec.xy_delta, axis=0, dtype=np.uint16)[idx, :n_all]
    delta = q.copy()
    np.subtract(q[1:], q[:-1], out=delta[1:])
    status = rec.status[idx, :n_all]
    status = status.astype(np.uint8) if status.max(initial=0) < 255 else status.astype(np.int16)
    parts: list[tuple[str, np.ndarray]] = [
        ("xy_delta", delta),
        ("status", status),
        ("state", rec.state[idx, :n_all].astype(np.uint8)),
        ("kind", rec.kind[:n_all].astype(np.uint8)),
    ]
    if rec.link_offsets is not None and rec.link_pairs is not None:
        chunks = [rec.link_pairs[rec.link_offsets[f]: rec.link_offsets[f + 1]] for f in idx]
        offsets = np.zeros(len(idx) + 1, dtype=np.int32)
        np.cumsum([len(c) for c in chunks], out=offsets[1:])
        pairs = np.concatenate(chunks).astype(np.int32) if offsets[-1] else np.zeros((0, 2), np.int32)
        parts += [("link_offsets", offsets), ("link_pairs", pairs)]
    parts += list(extra)
    arrays: dict[str, Any] = {}
    blobs: list[bytes] = []
    offset = 0
    for name, arr in parts:
        data = np.ascontiguousarray(arr).astype(arr.dtype.newbyteorder("<"), copy=False).tobytes()
        arrays[name] = {"dtype": arr.dtype.name, "offset": offset, "length": int(arr.size)}
        pad = (-len(data)) % 4
        blobs.append(data + b"\0" * pad)
        offset += len(data) + pad
    return b"".join(blobs), arrays


def replay_html(rec: Recording, folder: str | Path | None = None, *, every: int = 1,
                max_frames: int | None = None, layer: str = "coverage") -> bytes:
    """The replay page of a recording, as UTF-8 bytes.

    Args:
        rec: The recording.
        folder: The run folder, for ``timeseries.csv`` and ``summary.json`` (optional).
        every: Keep every ``every``-th recorded frame.
        max_frames: Keep at most this many frames, spread evenly (the last always kept).
        layer: ``coverage`` (the page of old), or ``signal``: the page also carries the signal of every frame
            (:func:`signal_rasters`), shows it first and toggles between it and the uncovered area. A run under a
            radio other than the unit disk always carries the signal (its uncovered area is drawn from it).

    Returns:
        The complete HTML document.
    """
    folder = Path(folder) if folder is not None else None
    check_layer(layer)
    idx = pick_frames(rec.frames, every, max_frames)
    signal: dict[str, Any] | None = None
    extra: tuple[tuple[str, np.ndarray], ...] = ()
    if layer == "signal" or rec.meta.get("medium", "unit-disk") != "unit-disk":
        # under walls or shadowing the uncovered area is not a union of disks: the page takes it from the rasters
        rasters, frame_raster, signal = signal_rasters(rec, idx)
        extra = (("signal", rasters), ("signal_frame", frame_raster))
    raw, arrays = replay_payload(rec, idx, extra)
    omap = rec.omap
    x0, x1, y0, y1 = omap.extent
    base = map_image(omap, rec.reachable, None)  # row 0 = lowest y; the page draws it with y pointing up
    tint = np.zeros((*omap.shape, 4), dtype=np.uint8)
    tint[rec.reachable] = (*MAP_COLOURS["uncovered"], 255)
    summary: dict[str, Any] = {}
    if folder is not None and (folder / "summary.json").is_file():
        try:  # optional: a damaged summary.json (not JSON, not an object) only leaves its numbers out
            summary = json.loads((folder / "summary.json").read_text())
        except ValueError:
            summary = {}
        if not isinstance(summary, dict):
            summary = {}
    meta = rec.meta
    title = f"{meta['algorithm']} on {meta['map']}, seed {meta['seed']}"
    header = {
        "title": title,
        "meta": meta,
        "summary": {k: summary.get(k) for k in ("stop_reason", "nodes_total", "coverage", "connected_coverage",
                                                  "sim_time_s", "routers_total") if k in summary},
        "extent": [x0, y0, x1 - x0, y1 - y0],
        "rows": int(omap.shape[0]),
        "cols": int(omap.shape[1]),
        "resolution": float(omap.resolution),
        "r_c": rec.r_c,
        "frames": len(idx),
        "robots": int(rec.n[idx].max()),
        "t": [round(float(v), 6) for v in rec.t[idx]],
        "steps": [int(v) for v in rec.steps[idx]],
        "n": [int(v) for v in rec.n[idx]],
        "quantum": rec.xy_quantum,
        "xy_origin": [float(v) for v in rec.xy_origin],
        "arrays": arrays,
        "status_none": 255 if arrays["status"]["dtype"] == "uint8" else -1,
        "state_names": list(STATE_NAMES),
        "kind_names": list(ROLE_NAMES),
        "palette": [_hex(c) for c in PALETTE],
        "no_status": _hex(NO_STATUS),
        "link_thinning": LINK_THINNING,
        "map_colours": {k: "#{:02x}{:02x}{:02x}".format(*v) for k, v in MAP_COLOURS.items()},
        "map_png": _png_b64(base),
        "reach_png": _png_b64(tint),
        "has_unreachable": bool((omap.free & ~rec.reachable).any()),
        "occupied_rgb": [int(c) for c in MAP_LUT[1]],
        "timeseries": _timeseries(rec, folder, idx),
    }
    if signal is not None:
        header["signal"] = {**signal, "first": layer == "signal"}
    payload = base64.b64encode(zlib.compress(raw, 6)).decode("ascii")
    text = resources.files("amronet.viz").joinpath(TEMPLATE).read_text(encoding="utf-8")
    header_json = json.dumps(header, separators=(",", ":")).replace("</", "<\\/")
    page = (text.replace("__AMRONET_TITLE__", html.escape(f"amronet replay: {title}"))
                .replace("__AMRONET_HEADER__", header_json)
                .replace("__AMRONET_PAYLOAD__", payload))
    return page.encode("utf-8")
