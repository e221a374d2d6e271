"""How nodes, links, disks and trails look, shared by snapshots, animation frames and the replay page.

Routers are shaped by state (explore: hollow circle, reference: filled circle, triangle: triangle, hollow while
moving) and coloured by status (which base station; grey for none yet); a failed node is a dark cross, as in the
legend and the animation; links thin out and fade when there are many of them.
"""

from __future__ import annotations

import math
from collections.abc import Mapping

import matplotlib as mpl
import numpy as np
from matplotlib.axes import Axes
from matplotlib.collections import LineCollection
from matplotlib.lines import Line2D
from matplotlib.markers import MarkerStyle
from matplotlib.patches import Patch

from amronet.viz.decorations import marker_handle

__all__ = ["DEPLOYED", "DISK_EDGE_ALPHA", "DISK_FACE_ALPHA", "LINK_COLOUR", "LINK_THINNING", "NO_STATUS", "PALETTE",
           "STYLE", "draw_nodes", "draw_trails", "link_style", "status_colours", "status_handles"]

# marker, base size (pt^2), filled, z-order, legend label; drawn in this order.
STYLE: dict[str, tuple[str, float, bool, float, str]] = {
    "explore": ("o", 14.0, False, 3.0, "explore"),
    "dropped": ("o", 30.0, False, 3.5, "dropped (not relaying yet)"),
    "failed": ("x", 40.0, True, 3.6, "failed"),
    "relocating": ("D", 26.0, False, 4.5, "relocating (repair)"),
    "strip": ("p", 34.0, False, 4.5, "driving to its strip goal"),
    "reference": ("o", 30.0, True, 4.0, "reference"),
    "triangle-settled": ("^", 42.0, True, 4.0, "triangle (settled)"),
    "triangle": ("^", 42.0, False, 5.0, "triangle (moving)"),
    "base": ("s", 110.0, True, 6.0, "base station"),
    "agent": ("*", 150.0, True, 7.0, "agent"),
}
DEPLOYED = ("base", "reference", "triangle-settled")
NO_STATUS = (0.55, 0.55, 0.55, 1.0)
# tab10 without red and grey: red fills would mimic the "uncovered" tint, grey means "no status".
PALETTE = np.asarray(mpl.colormaps["tab10"].colors, dtype=float)[[0, 1, 2, 4, 5, 8, 9, 6]]
LINK_COLOUR = (0.45, 0.45, 0.45, 0.8)
LINK_WIDTH = 0.6
FEW_LINKS = 300  # up to this many links keep the full style; beyond, width and alpha shrink
MIN_LINK_WIDTH = 0.15
MIN_LINK_ALPHA = 0.2
LINK_THINNING = {"few": FEW_LINKS, "width": LINK_WIDTH, "alpha": LINK_COLOUR[3], "min_width": MIN_LINK_WIDTH,
                 "min_alpha": MIN_LINK_ALPHA}
"""The rule of :func:`link_style` as data, for the replay page, which applies it in the browser."""
DISK_FACE_ALPHA = 0.05
DISK_EDGE_ALPHA = 0.4


def status_colours(status: np.ndarray) -> np.ndarray:
    """RGBA colours ``(N, 4)``: tab10 (less red and grey) by ``status``, grey where it is negative."""
    out = np.empty((status.size, 4))
    out[:, :3] = PALETTE[np.mod(status, len(PALETTE))]
    out[:, 3] = 1.0
    out[status < 0] = NO_STATUS
    return out


def link_style(count: int) -> tuple[float, tuple[float, float, float, float]]:
    """Line width (points) and RGBA colour of ``count`` links, thinner and fainter the more there are.

    Up to 300 links are drawn 0.6 pt wide at alpha 0.8; beyond, both shrink with the square root of the count
    (to at least 0.15 pt and alpha 0.2), so thousands of links stay a light web instead of a grey mat that
    hides the nodes.
    """
    k = math.sqrt(FEW_LINKS / max(count, FEW_LINKS))
    return max(LINK_WIDTH * k, MIN_LINK_WIDTH), (*LINK_COLOUR[:3], max(LINK_COLOUR[3] * k, MIN_LINK_ALPHA))


def status_handles(groups: np.ndarray) -> list[Line2D]:
    """Legend handles of the statuses ``groups`` (sorted): one colour each while the palette lasts.

    Colours repeat after ``len(PALETTE)`` base stations, so the statuses beyond are summed up in one
    ``"... k more BS"`` entry instead of listing repeated colours.
    """
    handles = []
    for s in groups[: len(PALETTE)]:
        label = f"BS {s}" if s >= 0 else "no BS yet"
        handles.append(marker_handle("o", 7.0, status_colours(np.array([s]))[0], label, edge="none"))
    if len(groups) > len(PALETTE):
        handles.append(Line2D([], [], linestyle="none", label=f"... {len(groups) - len(PALETTE)} more BS"))
    return handles


def draw_nodes(ax: Axes, xy: np.ndarray, state: np.ndarray, colours: np.ndarray) -> list[Patch | Line2D]:
    """Scatter the nodes, one call per state present; return legend handles of those states."""
    shrink = float(np.clip(math.sqrt(300 / max(len(xy), 1)), 0.35, 1.0))
    handles: list[Patch | Line2D] = []
    for st, (marker, size, filled, z, label) in STYLE.items():
        sel = state == st
        if not sel.any():
            continue
        x, y = xy[sel].T
        if filled and not MarkerStyle(marker).is_filled():  # a line marker (failed: x) is all edge, drawn dark
            ax.scatter(x, y, s=size * shrink, marker=marker, c="0.15", linewidths=0.4, zorder=z)
        elif filled:
            ec = "black" if st in ("base", "agent") else "0.15"
            ax.scatter(
                x, y, s=size * shrink, marker=marker, c=colours[sel], edgecolors=ec, linewidths=0.4, zorder=z
            )
        else:
            ax.scatter(
                x, y, s=size * shrink, marker=marker, facecolors="none", edgecolors=colours[sel],
                linewidths=1.0, zorder=z,
            )  # fmt: skip
        handles.append(marker_handle(marker, math.sqrt(size), "0.45" if filled else "none", label))
    return handles


def draw_trails(
    ax: Axes, trails: Mapping[int, np.ndarray] | None, colours: np.ndarray, n: int
) -> Line2D | None:
    """Draw each node's trail as one polyline in its status colour (one collection); return a legend handle."""
    if not trails:
        return None
    segments, seg_colours = [], []
    for i, path in trails.items():
        path = np.asarray(path, dtype=float).reshape(-1, 2)
        if not 0 <= int(i) < n:
            raise ValueError(f"trails: node index {i} is not one of xy's {n} rows")
        if len(path) >= 2:
            segments.append(path)
            seg_colours.append(colours[int(i)])
    if not segments:
        return None
    ax.add_collection(LineCollection(segments, colors=seg_colours, linewidths=0.7, alpha=0.55, zorder=2.5))
    return Line2D([], [], color="0.35", linewidth=1.0, label="agent trail")
