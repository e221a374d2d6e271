"""Pictures of recordings: one frame as a snapshot (PNG or SVG), many frames as an animation (GIF or MP4).

A snapshot of a frame is the same picture as the run's ``snapshot.png`` (:func:`amronet.viz.snapshot_figure`),
with the agents' trails up to that frame. An animation draws the static parts of that picture once (map, axes,
legend, scale bar) and then, frame by frame, restores them and draws only the artists that change (uncovered
tint, disks, links, trails, one marker collection per state, the title's text). Measured on a 2-core machine
at the default 80 dpi (720 x 564 pixels; 34 robots, agent-assisted on office-32x32): about 27 ms per frame,
against 98 ms for a full redraw.

GIFs are written with Pillow, with one palette of 255 colours for all frames (median cut over a few of them),
so each frame stores only the box that changed, its unchanged pixels transparent: 1.2 MB instead of 9.0 MB for
200 frames of that run. MP4 needs the optional ``imageio-ffmpeg`` package (``pip install 'amronet[video]'``),
which ships its own ffmpeg.
"""

from __future__ import annotations

import math
from collections.abc import Iterator, Sequence
from pathlib import Path

import numpy as np
from matplotlib.collections import EllipseCollection, LineCollection, PathCollection
from matplotlib.image import AxesImage
from matplotlib.lines import Line2D
from PIL import Image
from scipy import sparse

from amronet.engine.robots import STATE_NAMES, Role, State
from amronet.errors import AmronetError
from amronet.outputs.recording import Recording
from amronet.viz.decorations import add_legend, add_scale_bar, legend_patch, marker_handle
from amronet.viz.nodestyle import (
    DEPLOYED,
    DISK_EDGE_ALPHA,
    DISK_FACE_ALPHA,
    LINK_COLOUR,
    STYLE,
    link_style,
    status_colours,
    status_handles,
)
from amronet.viz.signal import (
    COLORBAR_SPACE,
    SPAN_DB,
    add_signal_colorbar,
    coarse_grid,
    draw_threshold,
    signal_rgba,
    threshold_handle,
)
from amronet.viz.snapshot import MAP_COLOURS, draw_map, map_patch, new_map_figure, snapshot_figure

__all__ = [
    "LAYERS",
    "FrameRenderer",
    "check_animation_options",
    "check_frame_options",
    "check_layer",
    "frame_title",
    "pick_frames",
    "recording_snapshot",
    "write_animation",
]

_DEPLOYED_CODES = np.array([s in DEPLOYED for s in STATE_NAMES])
# GIF frame delays are whole hundredths of a second in 16 bits (at most 655.35 s), and browsers play delays
# under 20 ms at 100 ms: 0.01 to 50 frames per second. MP4 plays any rate; above 120 fps frames are wasted.
_MIN_FPS = 0.01
_MAX_FPS = {".gif": 50.0, ".mp4": 120.0}
# Colours of a GIF's one palette: 255 leaves an index free for the transparent "unchanged" pixels.
_GIF_COLOURS = 255


def frame_title(rec: Recording, f: int, coverage: float | None = None) -> str:
    """Title with the frame's key numbers: algorithm, map, seed, nodes, coverage (computed if not given), time."""
    fr = rec.frame(f)
    routers = fr["kind"] == Role.ROUTER
    deployed = _DEPLOYED_CODES[fr["state"]]
    nodes = int(np.count_nonzero(deployed & routers) + np.count_nonzero(fr["kind"] == Role.BASE))
    m = rec.meta
    return (f"{m['algorithm']} on {m['map']}, seed {m['seed']}: {nodes} nodes, "
            f"coverage {100 * (rec.coverage(f) if coverage is None else coverage):.1f} %, t = {rec.t[f]:g} s")


def check_frame_options(every: int = 1, max_frames: int | None = None) -> None:
    """Check the frame selection of `pick_frames` (cheap, before loading a recording).

    Raises:
        AmronetError: ``every`` is below 1 or ``max_frames`` below 2.
    """
    if every < 1:
        raise AmronetError(f"--every: {every} must be >= 1")
    if max_frames is not None and max_frames < 2:
        raise AmronetError(f"--max-frames: {max_frames} must be >= 2")


def check_animation_options(path: str | Path, fps: float = 10.0, every: int = 1,
                            max_frames: int | None = None) -> None:
    """Check the options of `write_animation` (cheap, before loading a recording).

    Raises:
        AmronetError: The suffix of ``path`` is neither ``.gif`` nor ``.mp4``, ``fps`` is outside 0.01-50 (GIF)
            or 0.01-120 (MP4), ``every`` or ``max_frames`` is out of range, or MP4 is asked for without
            ``imageio-ffmpeg``.
    """
    path = Path(path)
    fmt = path.suffix.lower()
    if fmt not in (".gif", ".mp4"):
        raise AmronetError(f"--out: {path.name!r} must end in .gif or .mp4")
    top = _MAX_FPS[fmt]
    if not (math.isfinite(fps) and _MIN_FPS <= fps <= top):
        raise AmronetError(f"--fps: {fps:g} must be between {_MIN_FPS:g} and {top:g} frames per second for "
                           f"{fmt[1:].upper()}, e.g. 10")
    check_frame_options(every, max_frames)
    if fmt == ".mp4":
        _mp4_writer()


def pick_frames(frames: int, every: int = 1, max_frames: int | None = None) -> np.ndarray:
    """Indices of the frames to draw: every ``every``-th, at most ``max_frames`` spread evenly, always the last.

    Raises:
        AmronetError: ``every`` or ``max_frames`` is not a positive integer.
    """
    check_frame_options(every, max_frames)
    idx = np.arange(0, frames, every)
    if idx[-1] != frames - 1:
        idx = np.append(idx, frames - 1)
    if max_frames is not None and len(idx) > max_frames:
        idx = idx[np.unique(np.rint(np.linspace(0, len(idx) - 1, max_frames)).astype(int))]
    return idx


def recording_snapshot(rec: Recording, f: int = -1, dpi: float = 120, layer: str = "coverage"):
    """The snapshot figure of frame ``f`` (default: the last) of a recording, with the agents' trails.

    ``layer``: ``coverage`` (uncovered cells tinted, disks of ``r_c``) or ``signal`` (the best RSSI of the
    routers and base nodes per cell, :mod:`amronet.viz.signal`).
    """
    f = range(rec.frames)[f]
    fr = rec.frame(f)
    kind, state = rec.names(f)
    check_layer(layer)
    if layer == "signal":
        extra = {"signal": rec.signal(f, floor_db=-SPAN_DB), "threshold_dbm": rec.medium.budget.threshold_dbm}
    else:
        extra = {"covered": rec.covered(f)}
    return snapshot_figure(
        rec.omap, xy=fr["xy"], kind=kind, state=state, status=fr["status"].astype(np.int64), r_c=rec.r_c,
        links=rec.links(f), reachable=rec.reachable, title=frame_title(rec, f), dpi=dpi, trails=rec.trails(f),
        **extra,
    )  # fmt: skip


LAYERS = ("coverage", "signal")
"""What the pictures of a run shade under the nodes: the uncovered cells, or the best signal per cell."""


def check_layer(layer: str) -> None:
    """Check a ``--layer`` option.

    Raises:
        AmronetError: ``layer`` is not one of :data:`LAYERS`.
    """
    if layer not in LAYERS:
        raise AmronetError(f"--layer: {layer!r} is not one of {', '.join(LAYERS)}")


def _area_weights(cells: int, pixels: int) -> sparse.csr_matrix:
    """Sparse ``(pixels, cells)`` matrix averaging map cells into pixels by overlapping length (rows sum to 1)."""
    edges = np.linspace(0.0, pixels, cells + 1)  # cell edges in pixel units
    rows, cols, vals = [], [], []
    for c in range(cells):
        lo, hi = edges[c], edges[c + 1]
        for p in range(int(lo), min(int(np.ceil(hi)), pixels)):
            overlap = min(hi, p + 1) - max(lo, p)
            if overlap > 0:
                rows.append(p)
                cols.append(c)
                vals.append(overlap)
    weights = sparse.csr_matrix((vals, (rows, cols)), shape=(pixels, cells))
    sums = np.asarray(weights.sum(axis=1)).ravel()
    return sparse.diags(1.0 / np.maximum(sums, 1e-12)) @ weights


class FrameRenderer:
    """One Agg figure of a recording, drawn once; each frame redraws only what changes (blitting).

    The map, axes, legend, scale bar and the title's place are drawn once into a background. For each frame
    the background is restored and only the animated artists are drawn on it: the uncovered-area tint (averaged
    from map cells to screen pixels with a fixed sparse matrix, so it needs no resampling), the disks, links,
    trails, one marker collection per state, and the title text. Do not ``savefig`` :attr:`fig`: a full draw
    leaves the animated artists out; use :meth:`render`.

    Args:
        rec: The recording.
        dpi: Resolution (the figure's size in inches is the snapshot's).
        layers: Which optional layers to draw, among ``disks``, ``links``, ``trails``, ``uncovered`` and
            ``signal`` (the best RSSI of the routers and base nodes per cell, with its threshold contour and a
            colour bar; evaluated on a grid of cells of about two pixels, and only again when the routers and
            base nodes moved).
    """

    def __init__(self, rec: Recording, dpi: float = 80,
                 layers: Sequence[str] = ("disks", "links", "trails", "uncovered")) -> None:
        self.rec, self.dpi, self.layers = rec, dpi, set(layers)
        signal = "signal" in self.layers
        self.fig, self.ax = new_map_figure(rec.omap, right=2.2 + COLORBAR_SPACE * signal, dpi=dpi)
        ax = self.ax
        image = draw_map(ax, rec.omap, reachable=rec.reachable)
        image.set_interpolation("antialiased")  # at animation sizes a cell is < 1 pixel: keep thin walls
        d = 2.0 * rec.r_c
        self.disks = EllipseCollection(d, d, 0.0, units="xy", offsets=np.zeros((0, 2)), offset_transform=ax.transData,
                                       linewidths=0.5, zorder=1.5)
        ax.add_collection(self.disks)
        self.links = LineCollection([], colors=[LINK_COLOUR], linewidths=0.6, zorder=2)
        ax.add_collection(self.links)
        self.trails = LineCollection([], linewidths=0.7, alpha=0.55, zorder=2.5)
        ax.add_collection(self.trails)
        shrink = float(np.clip(math.sqrt(300 / max(int(rec.n.max()), 1)), 0.35, 1.0))
        self.markers: dict[int, tuple[PathCollection, bool]] = {}
        present = np.unique(rec.state)
        handles = []
        for name, (marker, size, filled, z, label) in STYLE.items():
            code = STATE_NAMES.index(name)
            coll = ax.scatter([], [], s=size * shrink, marker=marker, linewidths=0.4 if filled else 1.0, zorder=z)
            self.markers[code] = (coll, filled)
            if code in present:
                handles.append(marker_handle(marker, math.sqrt(size), "0.45" if filled else "none", label))
        if not signal or "disks" in self.layers:
            handles.append(legend_patch((0.5, 0.5, 0.5, 0.15), f"comm. range $r_c$ = {rec.r_c:g} m", edge="0.4"))
        handles.append(Line2D([], [], color=LINK_COLOUR, linewidth=1.0, label="link"))
        if np.any(rec.kind == Role.AGENT):
            handles.append(Line2D([], [], color="0.35", linewidth=1.0, label="agent trail"))
        free = rec.omap.free
        threshold = rec.medium.budget.threshold_dbm if signal else float("nan")
        if signal:
            handles.append(threshold_handle(threshold))
        shown = {"occupied": True, "unreachable": bool((free & ~rec.reachable).any()), "covered": not signal,
                 "uncovered": not signal}
        handles += [map_patch(c) for c, show in shown.items() if show]
        handles += status_handles(np.unique(rec.status))
        if signal:
            add_signal_colorbar(self.fig, ax, threshold)
            add_legend(self.fig, ax, handles, offset=COLORBAR_SPACE)
        else:
            add_legend(self.fig, ax, handles)
        add_scale_bar(ax, rec.omap)
        self.title = ax.set_title("", fontsize=10)
        self.fig.canvas.draw()  # lay out once: ticks, legend, the axes' pixels
        self._tint, self._tint_rows, self._tint_cols = self._tint_layer()
        self._counted = free & rec.reachable
        self._signal = _SignalLayer(rec, ax, threshold) if signal else None
        self._animated = sorted([self._tint, self.disks, self.links, self.trails, *ax.spines.values(),
                                 *(coll for coll, _ in self.markers.values()), self.title,
                                 *([self._signal.image] if self._signal is not None else [])],
                                key=lambda a: a.get_zorder())
        for artist in self._animated:
            artist.set_animated(True)
        self.fig.canvas.draw()
        self._background = self.fig.canvas.copy_from_bbox(self.fig.bbox)

    def _tint_layer(self) -> tuple[AxesImage, sparse.csr_matrix, sparse.csr_matrix]:
        """The uncovered-area tint: an RGBA image with one pixel per screen pixel of the axes, and its weights."""
        omap, ax = self.rec.omap, self.ax
        box = ax.get_window_extent()
        width, height = max(round(box.width), 1), max(round(box.height), 1)
        rows, cols = omap.shape
        rgba = np.zeros((height, width, 4), dtype=np.uint8)
        rgba[..., :3] = MAP_COLOURS["uncovered"]
        tint = ax.imshow(rgba, extent=omap.extent, origin="lower", interpolation="nearest", zorder=0.5)
        ax.set_xlim(omap.extent[0], omap.extent[1])
        ax.set_ylim(omap.extent[2], omap.extent[3])
        self._tint_rgba = rgba
        return tint, _area_weights(rows, height).astype(np.float32), _area_weights(cols, width).astype(np.float32)

    def update(self, f: int) -> None:
        """Move every artist to frame ``f``."""
        rec = self.rec
        fr = rec.frame(f)
        xy, state, status = fr["xy"], fr["state"], fr["status"].astype(np.int64)
        colours = status_colours(status)
        covered = rec.covered(f)
        if "uncovered" in self.layers:
            holes = (self._counted & ~covered).astype(np.float32)
            alpha = (self._tint_cols @ (self._tint_rows @ holes).T).T  # cells averaged into pixels: (h, w)
            self._tint_rgba[..., 3] = np.rint(255 * np.clip(alpha, 0, 1))
            self._tint.set_data(self._tint_rgba)
        self._tint.set_visible("uncovered" in self.layers)
        if self._signal is not None:
            self._signal.update(f)
        deployed = _DEPLOYED_CODES[state] | (fr["kind"] == Role.BASE)
        if "disks" in self.layers:
            face, edge = colours[deployed].copy(), colours[deployed].copy()
            face[:, 3], edge[:, 3] = DISK_FACE_ALPHA, DISK_EDGE_ALPHA
            self.disks.set_offsets(xy[deployed] if deployed.any() else np.zeros((0, 2)))
            self.disks.set_facecolor(face)
            self.disks.set_edgecolor(edge)
        if "links" in self.layers:
            links = rec.links(f)
            width, colour = link_style(len(links))
            self.links.set_segments(xy[links])
            self.links.set_linewidth(width)
            self.links.set_color(colour)
        if "trails" in self.layers:
            trails = rec.trails(f)
            self.trails.set_segments([p for p in trails.values()])
            self.trails.set_color([colours[i] for i in trails])
        for code, (coll, filled) in self.markers.items():
            sel = state == code
            coll.set_offsets(xy[sel] if sel.any() else np.zeros((0, 2)))
            if filled:
                coll.set_facecolor(colours[sel])
                coll.set_edgecolor("black" if code in (State.BASE, State.AGENT) else "0.15")
            else:
                coll.set_facecolor("none")
                coll.set_edgecolor(colours[sel])
        coverage = float(np.count_nonzero(covered) / max(np.count_nonzero(rec.reachable), 1))
        self.title.set_text(frame_title(rec, f, coverage=coverage))

    def render(self, f: int) -> np.ndarray:
        """The picture of frame ``f`` as ``uint8`` RGB ``(height, width, 3)``."""
        self.update(f)
        canvas = self.fig.canvas
        canvas.restore_region(self._background)
        renderer = canvas.get_renderer()
        animated = self._animated
        if self._signal is not None and self._signal.contour is not None:
            animated = sorted([*animated, self._signal.contour], key=lambda a: a.get_zorder())
        for artist in animated:
            artist.draw(renderer)
        return np.asarray(canvas.buffer_rgba())[..., :3].copy()

    def frames(self, indices: Sequence[int]) -> Iterator[np.ndarray]:
        """Render the frames ``indices`` one after another."""
        for f in indices:
            yield self.render(int(f))


_SIGNAL_PIXELS = 2.0
"""An animation's signal grid has cells of at least this many pixels a side (a signal map costs per cell)."""


class _SignalLayer:
    """The signal of a recording's frames on an animation's axes: an image and the threshold contour.

    The signal is evaluated on a grid with cells of at least :data:`_SIGNAL_PIXELS` pixels a side
    (:func:`~amronet.viz.signal.coarse_grid`), and again only when the routers and base nodes moved since the last
    frame drawn.
    """

    def __init__(self, rec: Recording, ax, threshold: float) -> None:
        self.rec, self.ax, self.threshold = rec, ax, threshold
        box = ax.get_window_extent()
        self.grid, self.k = coarse_grid(rec.omap, max(round(max(box.width, box.height) / _SIGNAL_PIXELS), 1))
        x0, _, y0, _ = rec.omap.extent
        rows, cols = self.grid.shape
        self.extent = (x0, x0 + cols * self.grid.resolution, y0, y0 + rows * self.grid.resolution)
        self.counted = rec.omap.free & rec.reachable
        centre_r = np.minimum(np.arange(rows) * self.k + self.k // 2, rec.omap.shape[0] - 1)
        centre_c = np.minimum(np.arange(cols) * self.k + self.k // 2, rec.omap.shape[1] - 1)
        self.shown = self.counted[np.ix_(centre_r, centre_c)]
        limits = ax.get_xlim(), ax.get_ylim()
        # the image has the map's cells (the coarse values repeated), so that walls keep their exact shape
        self.image = ax.imshow(np.zeros((*rec.omap.shape, 4), np.uint8), extent=rec.omap.extent, origin="lower",
                               interpolation="antialiased", zorder=0.5)
        ax.set_xlim(*limits[0])
        ax.set_ylim(*limits[1])
        self.contour = None
        self._key: bytes | None = None

    def update(self, f: int) -> None:
        xy = np.ascontiguousarray(self.rec.network_xy(f))
        key = xy.tobytes()
        if key == self._key:
            return
        self._key = key
        signal = self.rec.signal(f, grid=self.grid, floor_db=-SPAN_DB)
        rows, cols = self.rec.omap.shape
        fine = np.repeat(np.repeat(signal, self.k, axis=0), self.k, axis=1)
        fine = np.pad(fine, ((0, rows - fine.shape[0]), (0, cols - fine.shape[1])), mode="edge")
        self.image.set_data(signal_rgba(fine, self.threshold, self.counted))
        if self.contour is not None:
            self.contour.remove()
        self.contour = draw_threshold(self.ax, self.extent, signal, self.threshold, self.shown)
        if self.contour is not None:
            self.contour.set_animated(True)


def _gif_palette(renderer: FrameRenderer, indices: np.ndarray, colours: int = _GIF_COLOURS) -> Image.Image:
    """One palette for all frames of a GIF: median cut over a few frames spread over the run."""
    picks = indices[np.unique(np.rint(np.linspace(0, len(indices) - 1, min(len(indices), 5))).astype(int))]
    sample = np.concatenate([renderer.render(int(f)) for f in picks], axis=0)
    return Image.fromarray(sample).quantize(colors=colours, method=Image.Quantize.MEDIANCUT,
                                            dither=Image.Dither.NONE)


def _mp4_writer():
    try:
        import imageio_ffmpeg
    except ImportError:
        raise AmronetError("--out: writing .mp4 needs an encoder: pip install 'amronet[video]' (imageio-ffmpeg), "
                           "or write a .gif") from None
    return imageio_ffmpeg


def write_animation(rec: Recording, path: str | Path, *, fps: float = 10.0, every: int = 1,
                    max_frames: int | None = 200, dpi: float = 80, layer: str = "coverage") -> int:
    """Write an animation of a recording as GIF or MP4 (by the suffix of ``path``).

    Args:
        rec: The recording.
        path: Output file, ``.gif`` or ``.mp4``.
        fps: Frames per second of the animation: 0.01 to 50 for a GIF (its delays are in hundredths of a
            second, and browsers slow delays under 20 ms down to 100 ms), 0.01 to 120 for an MP4.
        every: Draw every ``every``-th recorded frame.
        max_frames: Draw at most this many frames, spread evenly over the run (the last always included).
        dpi: Resolution.
        layer: ``coverage`` (uncovered tint and disks) or ``signal`` (the best RSSI per cell, see
            :class:`FrameRenderer`; slower: each frame whose network moved costs a signal map).

    Returns:
        The number of frames written.

    Raises:
        AmronetError: An option is out of range (see `check_animation_options`), or MP4 is asked for without
            ``imageio-ffmpeg``.
    """
    path = Path(path)
    check_animation_options(path, fps, every, max_frames)
    check_layer(layer)
    ffmpeg = _mp4_writer() if path.suffix.lower() == ".mp4" else None
    indices = pick_frames(rec.frames, every, max_frames)
    layers = ("disks", "links", "trails", "uncovered") if layer == "coverage" else ("links", "trails", "signal")
    renderer = FrameRenderer(rec, dpi=dpi, layers=layers)
    if ffmpeg is None:
        palette = _gif_palette(renderer, indices)
        images = (Image.fromarray(rgb).quantize(palette=palette, dither=Image.Dither.NONE)
                  for rgb in renderer.frames(indices))
        # One palette for every frame: unchanged pixels keep their index, so Pillow stores each frame as the
        # box that changed, with unchanged pixels in it transparent (optimize), which LZW packs tightly.
        next(images).save(path, format="GIF", save_all=True, append_images=images, duration=round(1000 / fps),
                          loop=0, optimize=True, disposal=1)
        return len(indices)
    h, w = renderer.render(0).shape[:2]
    h2, w2 = h + h % 2, w + w % 2  # yuv420p wants even sides
    writer = ffmpeg.write_frames(str(path), (w2, h2), fps=fps, codec="libx264", pix_fmt_out="yuv420p",
                                 macro_block_size=2, quality=7, ffmpeg_log_level="error")
    writer.send(None)
    try:
        for rgb in renderer.frames(indices):
            frame = np.full((h2, w2, 3), 255, dtype=np.uint8)
            frame[:h, :w] = rgb
            writer.send(np.ascontiguousarray(frame))
    finally:
        writer.close()
    return len(indices)
