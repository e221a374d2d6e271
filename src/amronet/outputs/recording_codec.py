"""The compact array codec of recordings: quantized positions as frame-to-frame differences, small statuses.

Positions are quantized on a grid of ``quantum`` metres from ``origin`` and stored as uint16 differences to the
previous frame (modulo 2**16), so robots that stand still cost nearly nothing after compression. Statuses fit
in uint8 with 255 for "no base station yet" while there are fewer than 255 base stations.
"""

from __future__ import annotations

import numpy as np

__all__ = ["FORMAT", "backfill", "decode_positions", "decode_status", "encode_positions", "encode_status", "pad"]

FORMAT = "amronet-recording/1"
"""The format of ``recording.npz`` (``meta["format"]``)."""
NO_STATUS_U8 = 255
Q_MAX = 65535


def pad(frames: list[np.ndarray], n_all: int, tail: tuple[int, ...], dtype: type) -> np.ndarray:
    """Stack per-frame arrays of growing length into ``(F, n_all, *tail)``; missing rows are zero."""
    out = np.zeros((len(frames), n_all, *tail), dtype=dtype)
    for f, arr in enumerate(frames):  # one copy per frame, not per robot
        out[f, : len(arr)] = arr
    return out


def backfill(n: np.ndarray, *arrays: np.ndarray) -> None:
    """Give robots not yet present in a frame the values of the frame in which they first appear (in place)."""
    n_all = arrays[0].shape[1]
    first = np.searchsorted(n, np.arange(n_all), side="right")  # first frame where robot i is present
    if not np.any(first):
        return
    f_idx, i_idx = np.nonzero(np.arange(len(n))[:, None] < first[None, :])
    for arr in arrays:
        arr[f_idx, i_idx] = arr[first[i_idx], i_idx]


def encode_positions(xy: np.ndarray, origin: np.ndarray, quantum: float) -> np.ndarray:
    """Quantize positions ``(F, N, 2)`` and return frame-to-frame differences modulo 2**16 as uint16.

    Args:
        xy: Positions in metres ``(F, N, 2)``.
        origin: World point of quantum 0 ``(2,)`` (the map's lower-left corner).
        quantum: Metres per step of the grid.

    Returns:
        ``uint16`` ``(F, N, 2)``: ``q[0]``, then ``q[f] - q[f - 1]`` modulo 65 536.
    """
    q = np.rint((np.asarray(xy, dtype=np.float64) - origin) / quantum)
    q = np.clip(q, 0, Q_MAX).astype(np.uint16)
    delta = q.copy()
    np.subtract(q[1:], q[:-1], out=delta[1:])  # uint16 arithmetic wraps modulo 2**16
    return delta


def decode_positions(delta: np.ndarray, origin: np.ndarray, quantum: float) -> np.ndarray:
    """Invert :func:`encode_positions`: float32 positions ``(F, N, 2)`` in metres."""
    q = np.cumsum(delta, axis=0, dtype=np.uint16)
    return (q * quantum + origin).astype(np.float32)


def encode_status(status: np.ndarray) -> np.ndarray:
    """uint8 statuses (-1 wraps to 255) when every status fits, else int16."""
    if status.size == 0 or status.max() < NO_STATUS_U8:
        return status.astype(np.uint8)  # -1 wraps to 255
    return status.astype(np.int16)


def decode_status(status: np.ndarray) -> np.ndarray:
    """Invert :func:`encode_status`: int16 statuses with -1 for "no base station yet"."""
    if status.dtype == np.uint8:
        out = status.astype(np.int16)
        out[status == NO_STATUS_U8] = -1
        return out
    return status.astype(np.int16)
