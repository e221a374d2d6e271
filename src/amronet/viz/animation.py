"""Animations of recordings, GIF or MP4, from the frames :class:`~amronet.viz.frame_renderer.FrameRenderer` draws.

GIFs are written with Pillow, with one palette of 255 colours for all frames (median cut over a few of them),
so each frame stores only the box that changed, its unchanged pixels transparent: 1.2 MB instead of 9.0 MB for
200 frames of that run. MP4 needs the optional ``imageio-ffmpeg`` package (``pip install 'amronet[video]'``),
which ships its own ffmpeg.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
from PIL import Image

from amronet.errors import AmronetError
from amronet.outputs.recording import Recording
from amronet.viz.frame_renderer import FrameRenderer
from amronet.viz.frames import check_frame_options, check_layer, pick_frames

__all__ = ["check_animation_options", "write_animation"]

# GIF frame delays are whole hundredths of a second in 16 bits (at most 655.35 s), and browsers play delays
# under 20 ms at 100 ms: 0.01 to 50 frames per second. MP4 plays any rate; above 120 fps frames are wasted.
_MIN_FPS = 0.01
_MAX_FPS = {".gif": 50.0, ".mp4": 120.0}
# Colours of a GIF's one palette: 255 leaves an index free for the transparent "unchanged" pixels.
_GIF_COLOURS = 255


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
