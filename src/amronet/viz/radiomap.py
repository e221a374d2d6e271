"""The radio map: the predicted signal of a few nodes over a map, to scale (``amronet radio-map``).

The picture is the map (walls and unknown space drawn as in every map picture) with the best RSSI of the nodes per
free cell on the scale of :mod:`amronet.viz.signal`, the usable threshold's contour, the nodes, a colour bar in dBm
with the threshold marked, a legend and a scale bar.
"""

from __future__ import annotations

import numpy as np
from matplotlib.figure import Figure

from amronet.viz.decorations import add_legend, add_scale_bar, marker_handle
from amronet.viz.signal import (
    COLORBAR_SPACE,
    add_signal_colorbar,
    blank_handle,
    draw_signal,
    has_blank,
    threshold_handle,
)
from amronet.viz.snapshot import draw_map, map_patch, new_map_figure
from amronet.world.occupancy import OCCUPIED, UNKNOWN, OccupancyMap

__all__ = ["radio_map_figure"]

_NODE = {"marker": "o", "size": 7.0, "face": "white", "edge": "black"}


def radio_map_figure(omap: OccupancyMap, xy: np.ndarray, signal: np.ndarray, threshold_dbm: float, *,
                     title: str = "", dpi: float = 150) -> Figure:
    """The radio map of nodes ``xy`` as an Agg figure.

    Args:
        omap: The map.
        xy: The nodes ``(N, 2)`` in metres.
        signal: Best RSSI in dBm per cell, ``omap.shape`` (``RadioMedium.signal_dbm``), NaN where blank.
        threshold_dbm: The radio's usable threshold.
        title: The figure's title.
        dpi: Resolution.

    Raises:
        ValueError: ``signal`` does not have the map's shape.
    """
    xy = np.asarray(xy, dtype=float).reshape(-1, 2)
    signal = np.asarray(signal, dtype=float)
    if signal.shape != omap.shape:
        raise ValueError(f"signal must have the map's shape {omap.shape}, got {signal.shape}")
    fig, ax = new_map_figure(omap, right=COLORBAR_SPACE + 1.7, dpi=dpi)
    draw_map(ax, omap)
    draw_signal(ax, omap.extent, signal, threshold_dbm, omap.free)
    ax.scatter(xy[:, 0], xy[:, 1], s=_NODE["size"] ** 2, marker=_NODE["marker"], facecolors=_NODE["face"],
               edgecolors=_NODE["edge"], linewidths=1.0, zorder=5)
    handles = [marker_handle(_NODE["marker"], _NODE["size"], _NODE["face"], "node" if len(xy) == 1 else "nodes",
                             edge=_NODE["edge"]),
               threshold_handle(threshold_dbm)]
    if has_blank(signal, omap.free):
        handles.append(blank_handle(threshold_dbm))
    cells = omap.cells
    handles += [map_patch(c) for c, present in (("occupied", (cells == OCCUPIED).any()),
                                                 ("unknown", (cells == UNKNOWN).any())) if present]
    add_signal_colorbar(fig, ax, threshold_dbm)
    add_legend(fig, ax, handles, offset=COLORBAR_SPACE)
    add_scale_bar(ax, omap)
    ax.set_title(title or f"{omap.name}: best RSSI of {len(xy)} node{'s' * (len(xy) != 1)}", fontsize=10)
    return fig
