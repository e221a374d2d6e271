"""Pictures of recordings: one frame as a snapshot (PNG or SVG), many frames as an animation (GIF or MP4).

A snapshot of a frame is the same picture as the run's ``snapshot.png`` (:func:`amronet.viz.snapshot_figure`),
with the agents' trails up to that frame. An animation draws the same picture once and then, frame by frame,
only moves its artists (map shading, disks, links, trails, one marker collection per state) and redraws the Agg
canvas — a few tens of milliseconds per frame instead of building a figure each time.

GIFs are written with Pillow; MP4 needs the optional ``imageio-ffmpeg`` package (``pip install
'amronet[video]'``), which ships its own ffmpeg.
"""

from __future__ import annotations

import math
from collections.abc import Iterator, Sequence
from pathlib import Path

import numpy as np
from matplotlib.collections import EllipseCollection, LineCollection, PathCollection
from matplotlib.lines import Line2D
from PIL import Image

from amronet.errors import AmronetError
from amronet.recording import Recording
from amronet.robots import STATE_NAMES, Kind, State
from amronet.viz.decorations import add_legend, add_scale_bar, legend_patch, marker_handle
from amronet.viz.snapshot import (
    _DEPLOYED,
    _DISK_EDGE_ALPHA,
    _DISK_FACE_ALPHA,
    _LINK_COLOUR,
    _PALETTE,
    _STYLE,
    _map_image,
    _map_patch,
    _new_figure,
    _status_colours,
    draw_map,
    snapshot_figure,
)

__all__ = ["FrameRenderer", "frame_title", "pick_frames", "recording_snapshot", "write_animation"]

_DEPLOYED_CODES = np.array([s in _DEPLOYED for s in STATE_NAMES])
# GIF frame delays are whole hundredths of a second in 16 bits (at most 655.35 s), and browsers play delays
# under 20 ms at 100 ms: 0.01 to 50 frames per second. MP4 plays any rate; above 120 fps frames are wasted.
_MIN_FPS = 0.01
_MAX_FPS = {".gif": 50.0, ".mp4": 120.0}


def frame_title(rec: Recording, f: int) -> str:
    """Title with the frame's key numbers: algorithm, map, seed, nodes, coverage and time."""
    fr = rec.frame(f)
    routers = fr["kind"] == Kind.ROUTER
    deployed = _DEPLOYED_CODES[fr["state"]]
    nodes = int(np.count_nonzero(deployed & routers) + np.count_nonzero(fr["kind"] == Kind.BASE))
    m = rec.meta
    return (f"{m['algorithm']} on {m['map']}, seed {m['seed']}: {nodes} nodes, "
            f"coverage {100 * rec.coverage(f):.1f} %, t = {rec.t[f]:g} s")


def pick_frames(frames: int, every: int = 1, max_frames: int | None = None) -> np.ndarray:
    """Indices of the frames to draw: every ``every``-th, at most ``max_frames`` spread evenly, always the last.

    Raises:
        AmronetError: ``every`` or ``max_frames`` is not a positive integer.
    """
    if every < 1:
        raise AmronetError(f"--every: {every} must be >= 1")
    if max_frames is not None and max_frames < 2:
        raise AmronetError(f"--max-frames: {max_frames} must be >= 2")
    idx = np.arange(0, frames, every)
    if idx[-1] != frames - 1:
        idx = np.append(idx, frames - 1)
    if max_frames is not None and len(idx) > max_frames:
        idx = idx[np.unique(np.rint(np.linspace(0, len(idx) - 1, max_frames)).astype(int))]
    return idx


def recording_snapshot(rec: Recording, f: int = -1, dpi: float = 120):
    """The snapshot figure of frame ``f`` (default: the last) of a recording, with the agents' trails."""
    f = range(rec.frames)[f]
    fr = rec.frame(f)
    kind, state = rec.names(f)
    return snapshot_figure(
        rec.omap, xy=fr["xy"], kind=kind, state=state, status=fr["status"].astype(np.int64), r_c=rec.r_c,
        links=rec.links(f), covered=rec.covered(f), reachable=rec.reachable, title=frame_title(rec, f), dpi=dpi,
        trails=rec.trails(f),
    )  # fmt: skip


class FrameRenderer:
    """One Agg figure of a recording whose artists are updated for each frame.

    Args:
        rec: The recording.
        dpi: Resolution (the figure's size in inches is the snapshot's).
        layers: Which optional layers to draw, among ``disks``, ``links``, ``trails``, ``uncovered``.
    """

    def __init__(self, rec: Recording, dpi: float = 80,
                 layers: Sequence[str] = ("disks", "links", "trails", "uncovered")) -> None:
        self.rec, self.dpi, self.layers = rec, dpi, set(layers)
        self.fig, self.ax = _new_figure(rec.omap, right=2.2, dpi=dpi)
        ax = self.ax
        self.image = draw_map(ax, rec.omap, reachable=rec.reachable)
        self.image.set_interpolation("antialiased")  # at animation sizes a cell is < 1 pixel: keep thin walls
        d = 2.0 * rec.r_c
        self.disks = EllipseCollection(d, d, 0.0, units="xy", offsets=np.zeros((0, 2)), offset_transform=ax.transData,
                                       linewidths=0.5, zorder=1.5)
        ax.add_collection(self.disks)
        self.links = LineCollection([], colors=[_LINK_COLOUR], linewidths=0.6, zorder=2)
        ax.add_collection(self.links)
        self.trails = LineCollection([], linewidths=0.7, alpha=0.55, zorder=2.5)
        ax.add_collection(self.trails)
        shrink = float(np.clip(math.sqrt(300 / max(int(rec.n.max()), 1)), 0.35, 1.0))
        self.markers: dict[int, tuple[PathCollection, bool]] = {}
        present = np.unique(rec.state)
        handles = []
        for name, (marker, size, filled, z, label) in _STYLE.items():
            code = STATE_NAMES.index(name)
            coll = ax.scatter([], [], s=size * shrink, marker=marker, linewidths=0.4 if filled else 1.0, zorder=z)
            self.markers[code] = (coll, filled)
            if code in present:
                handles.append(marker_handle(marker, math.sqrt(size), "0.45" if filled else "none", label))
        handles.append(legend_patch((0.5, 0.5, 0.5, 0.15), f"comm. range $r_c$ = {rec.r_c:g} m", edge="0.4"))
        handles.append(Line2D([], [], color=_LINK_COLOUR, linewidth=1.0, label="link"))
        if np.any(rec.kind == Kind.AGENT):
            handles.append(Line2D([], [], color="0.35", linewidth=1.0, label="agent trail"))
        free = rec.omap.free
        shown = {"occupied": True, "unreachable": bool((free & ~rec.reachable).any()), "covered": True,
                 "uncovered": True}
        handles += [_map_patch(c) for c, show in shown.items() if show]
        for s in np.unique(rec.status)[: len(_PALETTE)]:
            handles.append(marker_handle("o", 7.0, _status_colours(np.array([s]))[0], f"BS {s}" if s >= 0 else
                                         "no BS yet", edge="none"))
        add_legend(self.fig, ax, handles)
        add_scale_bar(ax, rec.omap)
        self.title = ax.set_title("", fontsize=10)

    def update(self, f: int) -> None:
        """Move every artist to frame ``f``."""
        rec = self.rec
        fr = rec.frame(f)
        xy, state, status = fr["xy"], fr["state"], fr["status"].astype(np.int64)
        colours = _status_colours(status)
        covered = rec.covered(f) if "uncovered" in self.layers else None
        self.image.set_data(_map_image(rec.omap, rec.reachable, covered))
        deployed = _DEPLOYED_CODES[state] | (fr["kind"] == Kind.BASE)
        if "disks" in self.layers:
            face, edge = colours[deployed].copy(), colours[deployed].copy()
            face[:, 3], edge[:, 3] = _DISK_FACE_ALPHA, _DISK_EDGE_ALPHA
            self.disks.set_offsets(xy[deployed] if deployed.any() else np.zeros((0, 2)))
            self.disks.set_facecolor(face)
            self.disks.set_edgecolor(edge)
        if "links" in self.layers:
            self.links.set_segments(xy[rec.links(f)])
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
        self.title.set_text(frame_title(rec, f))

    def render(self, f: int) -> np.ndarray:
        """The picture of frame ``f`` as ``uint8`` RGB ``(height, width, 3)``."""
        self.update(f)
        self.fig.canvas.draw()
        return np.asarray(self.fig.canvas.buffer_rgba())[..., :3].copy()

    def frames(self, indices: Sequence[int]) -> Iterator[np.ndarray]:
        """Render the frames ``indices`` one after another."""
        for f in indices:
            yield self.render(int(f))


def _mp4_writer():
    try:
        import imageio_ffmpeg
    except ImportError:
        raise AmronetError("--out: writing .mp4 needs an encoder: pip install 'amronet[video]' (imageio-ffmpeg), "
                           "or write a .gif") from None
    return imageio_ffmpeg


def write_animation(rec: Recording, path: str | Path, *, fps: float = 10.0, every: int = 1,
                    max_frames: int | None = 200, dpi: float = 80) -> int:
    """Write an animation of a recording as GIF or MP4 (by the suffix of ``path``).

    Args:
        rec: The recording.
        path: Output file, ``.gif`` or ``.mp4``.
        fps: Frames per second of the animation: 0.01 to 50 for a GIF (its delays are in hundredths of a
            second, and browsers slow delays under 20 ms down to 100 ms), 0.01 to 120 for an MP4.
        every: Draw every ``every``-th recorded frame.
        max_frames: Draw at most this many frames, spread evenly over the run (the last always included).
        dpi: Resolution.

    Returns:
        The number of frames written.

    Raises:
        AmronetError: The suffix is neither ``.gif`` nor ``.mp4``, ``fps`` is outside 0.01-50 (GIF) or 0.01-120
            (MP4), or MP4 is asked for without ``imageio-ffmpeg``.
    """
    path = Path(path)
    fmt = path.suffix.lower()
    if fmt not in (".gif", ".mp4"):
        raise AmronetError(f"--out: {path.name!r} must end in .gif or .mp4")
    top = _MAX_FPS[fmt]
    if not (math.isfinite(fps) and _MIN_FPS <= fps <= top):
        raise AmronetError(f"--fps: {fps:g} must be between {_MIN_FPS:g} and {top:g} frames per second for "
                           f"{fmt[1:].upper()}, e.g. 10")
    ffmpeg = _mp4_writer() if fmt == ".mp4" else None
    indices = pick_frames(rec.frames, every, max_frames)
    renderer = FrameRenderer(rec, dpi=dpi)
    if ffmpeg is None:
        images = [Image.fromarray(rgb).quantize(colors=255, method=Image.Quantize.MEDIANCUT, dither=Image.Dither.NONE)
                  for rgb in renderer.frames(indices)]
        images[0].save(path, format="GIF", save_all=True, append_images=images[1:], duration=round(1000 / fps),
                       loop=0, optimize=False, disposal=1)
        return len(images)
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
