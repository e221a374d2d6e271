"""Pictures of recordings: one frame as a snapshot (PNG or SVG), many frames as an animation (GIF or MP4).

A snapshot of a frame is the same picture as the run's ``snapshot.png`` (:func:`amronet.viz.snapshot_figure`),
with the agents' trails up to that frame. An animation (:mod:`~amronet.viz.animation`) draws the static parts of
that picture once (map, axes, legend, scale bar) and then, frame by frame, restores them and draws only the
artists that change (:mod:`~amronet.viz.frame_renderer`). Which frames, their titles and the layers are
:mod:`~amronet.viz.frames`'s. Their public names are importable from here.
"""

from __future__ import annotations

import numpy as np
from matplotlib.figure import Figure

from amronet.outputs.recording import Recording
from amronet.viz.animation import check_animation_options, write_animation
from amronet.viz.frame_renderer import FrameRenderer
from amronet.viz.frames import LAYERS, check_frame_options, check_layer, frame_title, pick_frames
from amronet.viz.signal import SPAN_DB
from amronet.viz.snapshot import Nodes, Shading, snapshot_figure

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


def recording_snapshot(rec: Recording, f: int = -1, dpi: float = 120, layer: str = "coverage") -> Figure:
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
    nodes = Nodes(xy=fr["xy"], kind=kind, state=state, status=fr["status"].astype(np.int64), r_c=rec.r_c,
                  links=rec.links(f), trails=rec.trails(f))
    return snapshot_figure(rec.omap, nodes, Shading(reachable=rec.reachable, **extra), title=frame_title(rec, f),
                           dpi=dpi)
