"""Maps to scale: the occupancy grid as a picture, its cell categories' colours, the fixed figure layout.

Everything is drawn on a ``matplotlib.figure.Figure`` with an Agg canvas, never through ``pyplot``, so the
functions work headless and from several threads at once. The figure layout is fixed in inches (it depends
only on the map's size, not on what is drawn), so successive pictures of one run line up pixel for pixel.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
from matplotlib.axes import Axes
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from matplotlib.image import AxesImage
from matplotlib.patches import Patch

from amronet.viz.decorations import add_legend, legend_patch, save_figure
from amronet.viz.validate import check_mask
from amronet.world.occupancy import FREE, OCCUPIED, UNKNOWN, OccupancyMap

__all__ = [
    "MAP_COLOURS",
    "MAP_LUT",
    "check_picture_path",
    "draw_map",
    "map_image",
    "map_patch",
    "new_map_figure",
    "save_map_picture",
    "save_picture",
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


def check_picture_path(path: str | Path) -> str:
    """Return ``"png"`` or ``"svg"`` from the suffix of ``path``, or raise ``ValueError``."""
    fmt = Path(path).suffix.lower().lstrip(".")
    if fmt not in ("png", "svg"):
        raise ValueError(f"path must end in .png or .svg, got {Path(path).name!r}")
    return fmt


def save_picture(fig: Figure, path: str | Path, dpi: float) -> Path:
    """Write ``fig`` as PNG or SVG according to the suffix of ``path``."""
    path = Path(path)
    save_figure(fig, path, check_picture_path(path), dpi, bbox_inches=None, facecolor="white")
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
    check_picture_path(path)
    fig, ax = new_map_figure(omap, right=1.3, dpi=dpi)
    draw_map(ax, omap)
    w, h = omap.size_m
    ax.set_title(f"{omap.name}: {w:.1f} m x {h:.1f} m, {omap.resolution:g} m/cell", fontsize=10)
    add_legend(fig, ax, [map_patch(c) for c in ("free", "occupied", "unknown")])
    return save_picture(fig, path, dpi)
