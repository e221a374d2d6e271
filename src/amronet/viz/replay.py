"""The replay viewer: one self-contained HTML page that plays a recorded run in any browser.

The page (``replay_template.html`` beside this module: vanilla JavaScript and one canvas, nothing fetched from
anywhere) gets its data embedded: a small JSON header (map extent, ``r_c``, times, robots per frame, the
coverage time series, colours) and one binary payload — the recording's typed arrays (``uint16`` position
deltas, ``uint8`` states, statuses and kinds) concatenated, zlib-compressed and base64-encoded. The page
inflates it with the browser's own ``DecompressionStream`` and integrates the deltas into a ``Float32Array``
of positions, so the page is about as large as ``recording.npz``. Links are recomputed in the page for each
frame from the positions and ``r_c`` with a uniform grid (unit-disk medium) or read from the stored edge list.

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
from PIL import Image

from amronet.engine.robots import ROLE_NAMES, STATE_NAMES
from amronet.outputs.recording import Recording
from amronet.viz.nodestyle import LINK_THINNING, NO_STATUS, PALETTE
from amronet.viz.recorded import pick_frames
from amronet.viz.snapshot import MAP_COLOURS, MAP_LUT, map_image

__all__ = ["TEMPLATE", "replay_html", "replay_payload"]

TEMPLATE = "replay_template.html"
"""Name of the page template (package data of ``amronet.viz``)."""


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


def replay_payload(rec: Recording, idx: np.ndarray) -> tuple[bytes, dict[str, Any]]:
    """The binary payload (uncompressed) of frames ``idx`` and the descriptors of its arrays.

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
                max_frames: int | None = None) -> bytes:
    """The replay page of a recording, as UTF-8 bytes.

    Args:
        rec: The recording.
        folder: The run folder, for ``timeseries.csv`` and ``summary.json`` (optional).
        every: Keep every ``every``-th recorded frame.
        max_frames: Keep at most this many frames, spread evenly (the last always kept).

    Returns:
        The complete HTML document.
    """
    folder = Path(folder) if folder is not None else None
    idx = pick_frames(rec.frames, every, max_frames)
    raw, arrays = replay_payload(rec, idx)
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
    payload = base64.b64encode(zlib.compress(raw, 6)).decode("ascii")
    text = resources.files("amronet.viz").joinpath(TEMPLATE).read_text(encoding="utf-8")
    header_json = json.dumps(header, separators=(",", ":")).replace("</", "<\\/")
    page = (text.replace("__AMRONET_TITLE__", html.escape(f"amronet replay: {title}"))
                .replace("__AMRONET_HEADER__", header_json)
                .replace("__AMRONET_PAYLOAD__", payload))
    return page.encode("utf-8")
