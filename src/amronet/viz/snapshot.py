"""Pictures of maps and deployments: the occupancy grid to scale, routers, their disks and links.

Everything is drawn on a ``matplotlib.figure.Figure`` with an Agg canvas, never through ``pyplot``, so the
functions work headless and from several threads at once. The figure layout is fixed in inches (it depends
only on the map's size, not on what is drawn), so successive snapshots of one run line up pixel for pixel.

Example:
    >>> save_snapshot("snap.png", omap, xy=xy, kind=kind, state=state, status=status,
    ...               r_c=1.0, links=links)  # doctest: +SKIP
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path

import numpy as np
from matplotlib.axes import Axes
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.collections import EllipseCollection, LineCollection
from matplotlib.figure import Figure
from matplotlib.image import AxesImage
from matplotlib.lines import Line2D
from matplotlib.patches import Patch

from amronet.viz.decorations import add_legend, add_scale_bar, legend_patch, save_figure
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
    "STATES",
    "draw_map",
    "link_style",
    "save_map_picture",
    "save_snapshot",
    "snapshot_figure",
]

MAP_COLOURS: dict[str, tuple[int, int, int]] = {
    "free": (255, 255, 255),
    "occupied": (30, 30, 30),
    "unknown": (150, 150, 150),
    "unreachable": (240, 230, 205),
    "uncovered": (250, 185, 185),
}
"""RGB colours (0-255) of the map's cell categories."""

_LABELS = {
    "free": "free",
    "occupied": "occupied",
    "unknown": "unknown",
    "unreachable": "free, unreachable",
    "uncovered": "reachable, uncovered",
    "covered": "covered: within $r_c$ of any\nrouter or base (moving too)",
}
_CATEGORIES = ("free", "occupied", "unknown", "unreachable", "uncovered")
MAP_LUT = np.array([MAP_COLOURS[c] for c in _CATEGORIES], dtype=np.uint8)

# Fixed layout, in inches.
_AX_LONG_SIDE = 6.0
_AX_MIN_SIDE = 1.5
_MARGIN_LEFT, _MARGIN_BOTTOM, _MARGIN_TOP = 0.8, 0.6, 0.45
_MIN_FIG_HEIGHT = 4.6


def map_image(omap: OccupancyMap, reachable: np.ndarray | None, covered: np.ndarray | None) -> np.ndarray:
    """Return the ``uint8`` RGB image ``(rows, cols, 3)`` of the map with the optional shadings."""
    cells = omap.cells
    cat = np.zeros(cells.shape, dtype=np.uint8)
    cat[cells == OCCUPIED] = 1
    cat[cells == UNKNOWN] = 2
    free = cells == FREE
    counted = free
    if reachable is not None:
        cat[free & ~reachable] = 3
        counted = free & reachable
    if covered is not None:
        cat[counted & ~covered] = 4
    return MAP_LUT[cat]


def draw_map(
    ax: Axes,
    omap: OccupancyMap,
    *,
    reachable: np.ndarray | None = None,
    covered: np.ndarray | None = None,
) -> AxesImage:
    """Draw an occupancy map to scale in metres on ``ax``.

    Free cells are white, occupied near-black, unknown mid-grey. The image uses ``omap.extent`` with
    ``origin='lower'``, so data coordinates are world metres.

    Args:
        ax: The axes to draw on.
        omap: The map.
        reachable: Optional boolean mask ``omap.shape``; free cells outside it are tinted pale beige, so the
            reader sees which free space does not count.
        covered: Optional boolean mask ``omap.shape``; counted free cells (reachable ones, or all free cells
            when ``reachable`` is None) that are not covered are tinted light red, so holes stand out.

    Returns:
        The image artist.

    Raises:
        ValueError: If a mask has the wrong shape or is not boolean.
    """
    reachable = check_mask("reachable", reachable, omap.shape)
    covered = check_mask("covered", covered, omap.shape)
    im = ax.imshow(
        map_image(omap, reachable, covered),
        extent=omap.extent,
        origin="lower",
        interpolation="nearest",
        zorder=0,
    )
    ax.set_aspect("equal")
    ax.set_xlim(omap.extent[0], omap.extent[1])
    ax.set_ylim(omap.extent[2], omap.extent[3])
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    return im


def new_map_figure(omap: OccupancyMap, right: float, dpi: float) -> tuple[Figure, Axes]:
    """Create an Agg figure whose axes hold the map to scale, with ``right`` inches free for a legend."""
    w, h = omap.size_m
    scale = _AX_LONG_SIDE / max(w, h)
    ax_w, ax_h = max(w * scale, _AX_MIN_SIDE), max(h * scale, _AX_MIN_SIDE)
    fig_w = _MARGIN_LEFT + ax_w + right
    fig_h = max(_MARGIN_BOTTOM + ax_h + _MARGIN_TOP, _MIN_FIG_HEIGHT)
    bottom = (fig_h - ax_h - _MARGIN_TOP + _MARGIN_BOTTOM) / 2  # centre the axes vertically
    fig = Figure(figsize=(fig_w, fig_h), dpi=dpi, facecolor="white")
    FigureCanvasAgg(fig)
    ax = fig.add_axes((_MARGIN_LEFT / fig_w, bottom / fig_h, ax_w / fig_w, ax_h / fig_h))
    return fig, ax


def map_patch(category: str) -> Patch:
    """Legend patch of one map cell category (``covered`` is free space drawn plain, like ``free``)."""
    colour = MAP_COLOURS["free" if category == "covered" else category]
    return legend_patch(tuple(c / 255 for c in colour), _LABELS[category])


def _format_of(path: str | Path) -> str:
    """Return ``"png"`` or ``"svg"`` from the suffix of ``path``, or raise ``ValueError``."""
    fmt = Path(path).suffix.lower().lstrip(".")
    if fmt not in ("png", "svg"):
        raise ValueError(f"path must end in .png or .svg, got {Path(path).name!r}")
    return fmt


def _save(fig: Figure, path: str | Path, dpi: float) -> Path:
    """Write ``fig`` as PNG or SVG according to the suffix of ``path``."""
    path = Path(path)
    save_figure(fig, path, _format_of(path), dpi, bbox_inches=None, facecolor="white")
    return path


def save_map_picture(omap: OccupancyMap, path: str | Path, *, dpi: float = 150) -> Path:
    """Write a picture of the map alone, to scale, with a title and a legend of cell types.

    The title reads ``"{name}: {w:.1f} m x {h:.1f} m, {res} m/cell"``.

    Args:
        omap: The map.
        path: Output file; ``.png`` or ``.svg``.
        dpi: Resolution of the PNG (and of the map raster inside an SVG).

    Returns:
        The path written.

    Raises:
        ValueError: If the suffix of ``path`` is neither ``.png`` nor ``.svg``.
    """
    _format_of(path)
    fig, ax = new_map_figure(omap, right=1.3, dpi=dpi)
    draw_map(ax, omap)
    w, h = omap.size_m
    ax.set_title(f"{omap.name}: {w:.1f} m x {h:.1f} m, {omap.resolution:g} m/cell", fontsize=10)
    add_legend(fig, ax, [map_patch(c) for c in ("free", "occupied", "unknown")])
    return _save(fig, path, dpi)


def snapshot_figure(
    omap: OccupancyMap,
    *,
    xy: np.ndarray,
    kind: np.ndarray,
    state: np.ndarray,
    status: np.ndarray,
    r_c: float,
    links: np.ndarray,
    covered: np.ndarray | None = None,
    reachable: np.ndarray | None = None,
    title: str = "",
    dpi: float = 150,
    trails: Mapping[int, np.ndarray] | None = None,
    signal: np.ndarray | None = None,
    threshold_dbm: float | None = None,
) -> Figure:
    """Build the deployment picture as an Agg figure (see `save_snapshot` for the arguments).

    Returns:
        The figure; its first axes holds the map in world metres.

    Raises:
        ValueError: If an argument has the wrong shape or an unknown value.
    """
    xy, kind, state, status, links = validate_nodes(xy, kind, state, status, links, float(r_c))
    reachable = check_mask("reachable", reachable, omap.shape)
    covered = check_mask("covered", covered, omap.shape)
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


def save_snapshot(
    path: str | Path,
    omap: OccupancyMap,
    *,
    xy: np.ndarray,
    kind: np.ndarray,
    state: np.ndarray,
    status: np.ndarray,
    r_c: float,
    links: np.ndarray,
    covered: np.ndarray | None = None,
    reachable: np.ndarray | None = None,
    title: str = "",
    dpi: float = 150,
    trails: Mapping[int, np.ndarray] | None = None,
    signal: np.ndarray | None = None,
    threshold_dbm: float | None = None,
) -> Path:
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
        xy: Node positions ``(N, 2)`` in metres.
        kind: ``(N,)`` strings in `KINDS`.
        state: ``(N,)`` strings in `STATES`.
        status: ``(N,)`` integers: the base station a node belongs to, -1 for none yet.
        r_c: Communication radius in metres.
        links: ``(M, 2)`` integer index pairs into ``xy``.
        covered: Optional boolean mask ``omap.shape`` of covered cells; reachable (or, without
            ``reachable``, free) cells not covered are tinted light red.
        reachable: Optional boolean mask ``omap.shape``; free cells outside it are tinted pale beige.
        title: Figure title; by default the map's name and the numbers of routers and agents.
        dpi: Resolution of the PNG (and of the map raster inside an SVG).
        trails: Optional node index → path ``(k, 2)`` in metres (agents' trails), drawn as thin lines in the
            node's status colour.
        signal: Optional best RSSI (dBm) per cell ``omap.shape`` (``RadioMedium.signal_dbm``), NaN where blank:
            drawn instead of the coverage tint (``covered`` is then ignored) and of the disks, on the scale of
            :mod:`amronet.viz.signal`, with the threshold contour and a colour bar.
        threshold_dbm: The radio's usable threshold; needed with ``signal``.

    Returns:
        The path written.

    Raises:
        ValueError: If an argument has the wrong shape or an unknown value, or the suffix is not .png/.svg.
    """
    _format_of(path)
    fig = snapshot_figure(
        omap,
        xy=xy,
        kind=kind,
        state=state,
        status=status,
        r_c=r_c,
        links=links,
        covered=covered,
        reachable=reachable,
        title=title,
        dpi=dpi,
        trails=trails,
        signal=signal,
        threshold_dbm=threshold_dbm,
    )
    return _save(fig, path, dpi)
