"""Deployment pictures: the map to scale with the routers, their disks, links and trails, or a signal layer.

The map itself, its colours and the fixed layout are :mod:`amronet.viz.maps`'s (re-exported here). A picture
takes the map, its :class:`Nodes` and a :class:`Shading` of the free cells.

Example:
    >>> save_snapshot("snap.png", omap, Nodes(xy=xy, kind=kind, state=state, status=status, r_c=1.0,
    ...                                       links=links))  # doctest: +SKIP
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import NamedTuple

import numpy as np
from matplotlib.collections import EllipseCollection, LineCollection
from matplotlib.figure import Figure
from matplotlib.lines import Line2D

from amronet.viz.decorations import add_legend, add_scale_bar, legend_patch
from amronet.viz.maps import (
    MAP_COLOURS,
    MAP_LUT,
    check_picture_path,
    draw_map,
    map_image,
    map_patch,
    new_map_figure,
    save_map_picture,
    save_picture,
)
from amronet.viz.nodestyle import (
    DEPLOYED,
    DISK_EDGE_ALPHA,
    DISK_FACE_ALPHA,
    LINK_COLOUR,
    draw_nodes,
    draw_trails,
    link_style,
    status_colours,
    status_handles,
)
from amronet.viz.signal import (
    COLORBAR_SPACE,
    add_signal_colorbar,
    blank_handle,
    draw_signal,
    has_blank,
    threshold_handle,
)
from amronet.viz.validate import KINDS, STATES, check_mask, validate_nodes
from amronet.world.occupancy import FREE, OCCUPIED, UNKNOWN, OccupancyMap

__all__ = [
    "KINDS",
    "MAP_COLOURS",
    "MAP_LUT",
    "NO_SHADING",
    "STATES",
    "Nodes",
    "Shading",
    "draw_map",
    "link_style",
    "map_image",
    "map_patch",
    "new_map_figure",
    "save_map_picture",
    "save_snapshot",
    "snapshot_figure",
]


class Nodes(NamedTuple):
    """The nodes of a deployment picture.

    Attributes:
        xy: Node positions ``(N, 2)`` in metres.
        kind: ``(N,)`` strings in `KINDS`.
        state: ``(N,)`` strings in `STATES`.
        status: ``(N,)`` integers: the base station a node belongs to, -1 for none yet.
        r_c: Communication radius in metres (the disks' radius).
        links: ``(M, 2)`` integer index pairs into ``xy``.
        trails: Optional node index → path ``(k, 2)`` in metres (agents' trails), drawn as thin lines in the
            node's status colour.
    """

    xy: np.ndarray
    kind: np.ndarray
    state: np.ndarray
    status: np.ndarray
    r_c: float
    links: np.ndarray
    trails: Mapping[int, np.ndarray] | None = None


class Shading(NamedTuple):
    """What a deployment picture shades the map's free cells with, under the nodes (each optional).

    Attributes:
        reachable: Boolean mask ``omap.shape``; free cells outside it are tinted pale beige.
        covered: Boolean mask ``omap.shape`` of covered cells; reachable (or, without ``reachable``, free) cells
            not covered are tinted light red.
        signal: Best RSSI (dBm) per cell ``omap.shape`` (``RadioMedium.signal_dbm``), NaN where blank: drawn
            instead of the coverage tint (``covered`` is then ignored) and of the disks, on the scale of
            :mod:`amronet.viz.signal`, with the threshold contour and a colour bar.
        threshold_dbm: The radio's usable threshold; needed with ``signal``.
    """

    reachable: np.ndarray | None = None
    covered: np.ndarray | None = None
    signal: np.ndarray | None = None
    threshold_dbm: float | None = None


NO_SHADING = Shading()
"""The map's free cells plain."""


def snapshot_figure(omap: OccupancyMap, nodes: Nodes, shading: Shading = NO_SHADING, *, title: str = "",
                    dpi: float = 150) -> Figure:
    """Build the deployment picture as an Agg figure (see `save_snapshot` for the arguments).

    Returns:
        The figure; its first axes holds the map in world metres.

    Raises:
        ValueError: If an argument has the wrong shape or an unknown value.
    """
    r_c, trails = float(nodes.r_c), nodes.trails
    xy, kind, state, status, links = validate_nodes(nodes.xy, nodes.kind, nodes.state, nodes.status, nodes.links, r_c)
    reachable = check_mask("reachable", shading.reachable, omap.shape)
    covered = check_mask("covered", shading.covered, omap.shape)
    signal, threshold_dbm = shading.signal, shading.threshold_dbm
    if signal is not None:
        signal = _check_signal(signal, threshold_dbm, omap.shape)
        covered = None
    fig, ax = new_map_figure(omap, right=2.2 if signal is None else 2.2 + COLORBAR_SPACE, dpi=dpi)
    draw_map(ax, omap, reachable=reachable, covered=covered)
    if signal is not None:
        shown = omap.free if reachable is None else omap.free & reachable
        draw_signal(ax, omap.extent, signal, threshold_dbm, shown)
    colours = status_colours(status)

    deployed = np.isin(state, DEPLOYED) | (kind == "base")
    if deployed.any() and signal is None:  # the signal shows the range; disks would tint its colours
        face = colours[deployed].copy()
        face[:, 3] = DISK_FACE_ALPHA
        edge = colours[deployed].copy()
        edge[:, 3] = DISK_EDGE_ALPHA
        d = 2.0 * r_c
        disks = EllipseCollection(
            d,
            d,
            0.0,
            units="xy",
            offsets=xy[deployed],
            offset_transform=ax.transData,
            facecolors=face,
            edgecolors=edge,
            linewidths=0.5,
            zorder=1.5,
        )
        ax.add_collection(disks)
    if len(links):
        width, colour = link_style(len(links))
        ax.add_collection(LineCollection(xy[links], colors=[colour], linewidths=width, zorder=2))

    trail_handle = draw_trails(ax, trails, colours, len(xy))
    handles = draw_nodes(ax, xy, state, colours)
    if trail_handle is not None:
        handles.append(trail_handle)
    if deployed.any() and signal is None:
        handles.append(legend_patch((0.5, 0.5, 0.5, 0.15), f"comm. range $r_c$ = {r_c:g} m", edge="0.4"))
    if len(links):
        handles.append(Line2D([], [], color=LINK_COLOUR, linewidth=1.0, label="link"))
    if signal is not None:
        handles.append(threshold_handle(threshold_dbm))
        if has_blank(signal, shown):
            handles.append(blank_handle(threshold_dbm))
    cells = omap.cells
    free = cells == FREE
    counted = free if reachable is None else free & reachable
    for category, shown in (
        ("occupied", (cells == OCCUPIED).any()),
        ("unknown", (cells == UNKNOWN).any()),
        ("unreachable", reachable is not None and (free & ~reachable).any()),
        ("covered", covered is not None and (counted & covered).any()),
        ("uncovered", covered is not None and (counted & ~covered).any()),
    ):
        if shown:
            handles.append(map_patch(category))
    handles += status_handles(np.unique(status))
    if signal is None:
        add_legend(fig, ax, handles)
    else:
        add_signal_colorbar(fig, ax, threshold_dbm)
        add_legend(fig, ax, handles, offset=COLORBAR_SPACE)
    add_scale_bar(ax, omap)

    if not title:
        n_routers = int(np.sum(kind == "router"))
        n_agents = int(np.sum(kind == "agent"))
        title = (
            f"{omap.name}: {n_routers} router{'s' * (n_routers != 1)}, "
            f"{n_agents} agent{'s' * (n_agents != 1)}"
        )
    ax.set_title(title, fontsize=10)
    return fig


def _check_signal(signal: np.ndarray, threshold_dbm: float | None, shape: tuple[int, int]) -> np.ndarray:
    """A signal grid must have the map's shape and come with a finite threshold."""
    signal = np.asarray(signal, dtype=float)
    if signal.shape != tuple(shape):
        raise ValueError(f"signal must have the map's shape {tuple(shape)}, got {signal.shape}")
    if threshold_dbm is None or not np.isfinite(threshold_dbm):
        raise ValueError(f"a signal layer needs the radio's finite threshold_dbm, got {threshold_dbm!r}")
    return signal


def save_snapshot(path: str | Path, omap: OccupancyMap, nodes: Nodes, shading: Shading = NO_SHADING, *,
                  title: str = "", dpi: float = 150) -> Path:
    """Write the deployment picture: map, communication disks, links and nodes.

    Base stations and deployed routers (``reference``, ``triangle-settled``) get a translucent disk of radius
    ``r_c``; links are thin grey lines; nodes are markers by state (base: large square, reference: filled
    circle, triangle-settled: filled triangle, triangle: hollow triangle, explore: small hollow circle,
    agent: star), coloured by ``status`` (tab10 without its red and grey, which would mimic the uncovered
    tint and "no status"; grey for -1). A legend sits right of the map, a scale bar below its lower right corner.
    Disks, links and each state's markers are one collection each, so thousands of nodes draw quickly.

    Args:
        path: Output file; ``.png`` or ``.svg``.
        omap: The map.
        nodes: The nodes, their links and trails (:class:`Nodes`).
        shading: What the free cells are shaded with (:class:`Shading`; default none).
        title: Figure title; by default the map's name and the numbers of routers and agents.
        dpi: Resolution of the PNG (and of the map raster inside an SVG).

    Returns:
        The path written.

    Raises:
        ValueError: If an argument has the wrong shape or an unknown value, or the suffix is not .png/.svg.
    """
    check_picture_path(path)
    return save_picture(snapshot_figure(omap, nodes, shading, title=title, dpi=dpi), path, dpi)
