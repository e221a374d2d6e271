"""Pictures of static pattern placements, one panel per pattern, like the paper's Fig. 6.

Each panel shows the area (a rectangle, or a map with the cells that count), the pattern's communication
disks (one ``EllipseCollection``), its unit-disk links (one ``LineCollection``), the nodes (r-strip connectors
as diamonds), the counted cells no disk covers tinted light red and, since such holes are often only a few
cells, every hole ringed in red (the paper's Fig. 6 circles them too). The title gives the pattern's name, the
placed count, the paper's estimate and the exact coverage. Drawn on a ``matplotlib.figure.Figure`` with an
Agg canvas, never through ``pyplot``.

Example:
    >>> from amronet.patterns import place_all
    >>> save_patterns_figure(place_all((32.0, 32.0), 4.0), (32.0, 32.0), 4.0, "patterns.png")  # doctest: +SKIP
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from pathlib import Path

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.collections import EllipseCollection, LineCollection
from matplotlib.figure import Figure
from matplotlib.lines import Line2D
from matplotlib.patches import Patch, Rectangle
from scipy import ndimage

from amronet.patterns import PatternArea, Placement, as_area, pattern_links
from amronet.viz.decorations import save_figure
from amronet.viz.snapshot import MAP_COLOURS, draw_map
from amronet.world.occupancy import OccupancyMap

__all__ = ["patterns_figure", "save_patterns_figure"]

_PANEL_IN = 4.2  # panel width and height in inches
_NODE = "#1f4e9a"
_CONNECTOR = "#e07b00"
_DISK_FACE = (0.12, 0.31, 0.6, 0.06)
_DISK_EDGE = (0.12, 0.31, 0.6, 0.45)
_LINK = (0.3, 0.3, 0.3, 0.8)
_HOLE = "#d62728"
_MAX_RINGS = 60


def _holes(area: PatternArea, covered: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Centres ``(k, 2)`` and radii ``(k,)`` of rings around the connected groups of uncovered counted cells."""
    labels, n = ndimage.label(area.mask & ~covered, structure=np.ones((3, 3), dtype=bool))
    if n == 0:
        return np.empty((0, 2)), np.empty(0)
    idx = np.arange(1, n + 1)
    rows, cols = np.nonzero(labels)
    lab = labels[rows, cols]
    size = np.bincount(lab, minlength=n + 1)[1:]
    order = idx[np.argsort(-size, kind="stable")][:_MAX_RINGS]
    res = area.omap.resolution
    centres, radii = [], []
    for k in order:
        sel = lab == k
        xy = area.omap.cell_centres(rows[sel], cols[sel])
        c = xy.mean(axis=0)
        centres.append(c)
        radii.append(float(np.max(np.hypot(*(xy - c).T))) + 2.5 * res)
    span = max(area.bounds[2] - area.bounds[0], area.bounds[3] - area.bounds[1])
    return np.array(centres), np.maximum(np.array(radii), span / 60)


def _panel(ax, area: PatternArea, p: Placement, r: float, name: str) -> None:
    """Draw one placement on ``ax``."""
    covered = area.coverage.covered_mask(p.xy, r) if p.count else np.zeros(area.mask.shape, dtype=bool)
    draw_map(ax, area.omap, reachable=None if area.rectangle is not None else area.mask, covered=covered)
    x0, y0, x1, y1 = area.bounds
    if area.rectangle is not None:
        ax.add_patch(Rectangle((x0, y0), x1 - x0, y1 - y0, fill=False, edgecolor="0.2", linewidth=1.0, zorder=1))
        pad = 0.04 * max(x1 - x0, y1 - y0)
        ax.set_xlim(x0 - pad, x1 + pad)
        ax.set_ylim(y0 - pad, y1 + pad)
    if p.count:
        ax.add_collection(EllipseCollection(
            2 * r, 2 * r, 0.0, units="xy", offsets=p.xy, offset_transform=ax.transData, facecolors=[_DISK_FACE],
            edgecolors=[_DISK_EDGE], linewidths=0.5, zorder=1.5,
        ))  # fmt: skip
        links = pattern_links(p.xy, r)
        if len(links):
            ax.add_collection(LineCollection(p.xy[links], colors=[_LINK], linewidths=0.8, zorder=2))
        conn = p.connector
        ax.scatter(*p.xy[~conn].T, s=14, c=_NODE, edgecolors="white", linewidths=0.4, zorder=4)
        if conn.any():
            ax.scatter(*p.xy[conn].T, s=26, marker="D", c=_CONNECTOR, edgecolors="black", linewidths=0.4, zorder=4)
    centres, radii = _holes(area, covered)
    if len(radii):
        ax.add_collection(EllipseCollection(
            2 * radii, 2 * radii, 0.0, units="xy", offsets=centres, offset_transform=ax.transData,
            facecolors="none", edgecolors=_HOLE, linewidths=1.2, zorder=5,
        ))  # fmt: skip
    flag = "" if p.connected else ", DISCONNECTED"
    ax.set_title(f"{name}: {p.count} placed (est. {p.estimate})\ncoverage {100 * p.coverage:.3f} %{flag}", fontsize=10)


def patterns_figure(
    placements: Mapping[str, Placement] | Sequence[Placement],
    area: tuple[float, float] | OccupancyMap | tuple[OccupancyMap, np.ndarray] | PatternArea,
    r: float,
    *,
    dpi: float = 120,
) -> Figure:
    """Build the figure (see :func:`save_patterns_figure` for the arguments).

    Returns:
        An Agg figure with one axes per placement (in world metres).

    Raises:
        ValueError: No placement, ``r`` not finite and positive, or a bad area.
    """
    items = list(placements.items()) if isinstance(placements, Mapping) else [(p.pattern, p) for p in placements]
    if not items:
        raise ValueError("placements is empty: nothing to draw")
    if not (isinstance(r, int | float) and math.isfinite(r) and r > 0):
        raise ValueError(f"r must be a finite number > 0, got {r!r}")
    pa = as_area(area, r=r)
    n = len(items)
    ncols = 2 if n == 4 else min(n, 3)
    nrows = math.ceil(n / ncols)
    x0, y0, x1, y1 = pa.omap.extent[0], pa.omap.extent[2], pa.omap.extent[1], pa.omap.extent[3]
    aspect = (y1 - y0) / (x1 - x0)
    panel_w = _PANEL_IN
    panel_h = float(np.clip(_PANEL_IN * aspect, 1.5, 2 * _PANEL_IN))
    size = (ncols * (panel_w + 0.9), nrows * (panel_h + 1.1) + 0.5)
    fig = Figure(figsize=size, dpi=dpi, facecolor="white", layout="constrained")
    FigureCanvasAgg(fig)
    axes = fig.subplots(nrows, ncols, squeeze=False)
    for ax, (name, p) in zip(axes.flat, items, strict=False):
        _panel(ax, pa, p, float(r), name)
    for ax in axes.flat[n:]:
        ax.set_visible(False)
    handles = [
        Line2D([], [], linestyle="none", marker="o", markersize=5, markerfacecolor=_NODE, markeredgecolor="white",
               label="node"),
        Line2D([], [], linestyle="none", marker="D", markersize=5, markerfacecolor=_CONNECTOR,
               markeredgecolor="black", label="r-strip connector"),
        Patch(facecolor=_DISK_FACE, edgecolor=_DISK_EDGE, label=f"comm. disk, r = {r:g} m"),
        Line2D([], [], color=_LINK, linewidth=1.0, label="link"),
        Patch(facecolor=tuple(c / 255 for c in MAP_COLOURS["uncovered"]), edgecolor="0.3", label="uncovered"),
        Line2D([], [], linestyle="none", marker="o", markersize=9, markerfacecolor="none", markeredgecolor=_HOLE,
               label="hole (ringed)"),
    ]  # fmt: skip
    fig.legend(handles=handles, loc="outside lower center", ncol=len(handles), fontsize=8, frameon=False)
    return fig


def save_patterns_figure(
    placements: Mapping[str, Placement] | Sequence[Placement],
    area: tuple[float, float] | OccupancyMap | tuple[OccupancyMap, np.ndarray] | PatternArea,
    r: float,
    path: str | Path,
    *,
    dpi: float = 120,
) -> Path:
    """Write one panel per placement, like the paper's Fig. 6.

    Args:
        placements: Pattern name to placement (e.g. from :func:`amronet.patterns.place_all`), or a sequence.
        area: The area they were placed in, as given to :func:`amronet.patterns.place`.
        r: Communication radius in metres.
        path: Output file, ``.png`` or ``.svg``.
        dpi: Resolution of the PNG (and of the map raster inside an SVG).

    Returns:
        The path written.

    Raises:
        ValueError: The suffix is neither ``.png`` nor ``.svg``, or see :func:`patterns_figure`.
    """
    path = Path(path)
    fmt = path.suffix.lower().lstrip(".")
    if fmt not in ("png", "svg"):
        raise ValueError(f"path must end in .png or .svg, got {path.name!r}")
    fig = patterns_figure(placements, area, r, dpi=dpi)
    save_figure(fig, path, fmt, dpi, facecolor="white")
    return path
