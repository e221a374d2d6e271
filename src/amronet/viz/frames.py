"""Frames of a recording: which to draw, what a frame's title says, which layer is shaded under the nodes."""

from __future__ import annotations

import numpy as np

from amronet.engine.robots import STATE_NAMES, Role
from amronet.errors import AmronetError
from amronet.outputs.recording import Recording
from amronet.viz.nodestyle import DEPLOYED

__all__ = ["DEPLOYED_CODES", "LAYERS", "check_frame_options", "check_layer", "frame_title", "pick_frames"]

DEPLOYED_CODES = np.array([s in DEPLOYED for s in STATE_NAMES])
"""By state code: whether a node in that state is deployed (it covers, it gets a disk)."""


def frame_title(rec: Recording, f: int, coverage: float | None = None) -> str:
    """Title with the frame's key numbers: algorithm, map, seed, nodes, coverage (computed if not given), time."""
    fr = rec.frame(f)
    routers = fr["kind"] == Role.ROUTER
    deployed = DEPLOYED_CODES[fr["state"]]
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


LAYERS = ("coverage", "signal")
"""What the pictures of a run shade under the nodes: the uncovered cells, or the best signal per cell."""


def check_layer(layer: str) -> None:
    """Check a ``--layer`` option.

    Raises:
        AmronetError: ``layer`` is not one of :data:`LAYERS`.
    """
    if layer not in LAYERS:
        raise AmronetError(f"--layer: {layer!r} is not one of {', '.join(LAYERS)}")
