"""Decorations shared by the pictures: the legend beside the map, legend handles, the scale bar, and saving.

:func:`save_figure` is how every picture is written: an SVG (or PDF) of the same figure is byte-identical from
one run to the next.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from pathlib import Path
from typing import IO, Any

import matplotlib as mpl
from matplotlib.axes import Axes
from matplotlib.figure import Figure
from matplotlib.lines import Line2D
from matplotlib.patches import Patch
from mpl_toolkits.axes_grid1.anchored_artists import AnchoredSizeBar

from amronet.world.occupancy import OccupancyMap

__all__ = ["GAP", "add_legend", "add_scale_bar", "legend_patch", "marker_handle", "nice_length", "save_figure"]

GAP = 0.15
"""Gap in inches between the map's axes and the legend."""

_SCALE_BAR_DROP = 0.27
"""Inches from the bottom of the map's axes down to the top of the scale bar: below the x tick labels."""


def add_legend(fig: Figure, ax: Axes, handles: Sequence[Patch | Line2D], offset: float = 0.0) -> None:
    """Place a legend of ``handles`` outside the axes, to the right of its top edge (``offset`` inches further)."""
    _, _, x1, y1 = ax.get_position().extents
    fig_w = fig.get_figwidth()
    fig.legend(
        handles=list(handles),
        loc="upper left",
        bbox_to_anchor=(x1 + (GAP + offset) / fig_w, y1),
        fontsize=8,
        frameon=False,
        borderaxespad=0.0,
        handlelength=1.6,
    )


def nice_length(width: float) -> float:
    """A round length (1, 2 or 5 times a power of ten) close to a fifth of ``width``."""
    target = width / 5
    exp = math.floor(math.log10(target))
    candidates = [m * 10.0**e for e in (exp, exp + 1) for m in (1, 2, 5)]
    return min(candidates, key=lambda c: abs(math.log(c / target)))


def marker_handle(marker: str, size: float, face: object, label: str, edge: object = "0.15") -> Line2D:
    """Legend handle showing one marker."""
    return Line2D(
        [], [], linestyle="none", marker=marker, markersize=size, markerfacecolor=face,
        markeredgecolor=edge, markeredgewidth=0.8, label=label,
    )  # fmt: skip


def legend_patch(face: object, label: str, edge: object = "0.3") -> Patch:
    """Legend handle showing a filled rectangle."""
    return Patch(facecolor=face, edgecolor=edge, linewidth=0.5, label=label)


def add_scale_bar(ax: Axes, omap: OccupancyMap) -> AnchoredSizeBar:
    """Add a scale bar of a round length, about a fifth of the map's width, below the map's lower right corner.

    The bar sits outside the axes, under the x tick labels and level with the x axis label, so it never hides
    a node; its length is still in data units (``ax.transData``), so it matches the map's scale.

    Returns:
        The scale bar artist (an ``AnchoredSizeBar`` added to ``ax``).
    """
    length = nice_length(omap.size_m[0])
    fig = ax.get_figure()
    _, y0, x1, _ = ax.get_position().extents
    fig_w, fig_h = fig.get_size_inches()
    bar = AnchoredSizeBar(
        ax.transData, length, f"{length:g} m", loc="upper right", pad=0.0, borderpad=0.0, sep=2,
        frameon=False, size_vertical=0, fontproperties={"size": 8},
        bbox_to_anchor=(x1 * fig_w, y0 * fig_h - _SCALE_BAR_DROP), bbox_transform=fig.dpi_scale_trans,
    )  # fmt: skip
    bar.size_bar.get_children()[0].set_linewidth(2.5)  # a zero-height rectangle: only its edge shows
    bar.set_clip_on(False)
    bar.set_zorder(8)
    ax.add_artist(bar)
    return bar


_NO_DATE: dict[str, dict[str, Any]] = {"svg": {"Date": None}, "pdf": {"CreationDate": None}}


def save_figure(fig: Figure, target: str | Path | IO[bytes], fmt: str, dpi: float, **kwargs: Any) -> None:
    """Save ``fig`` as ``fmt`` (``png``, ``svg``, ``pdf``) so that the same figure gives the same bytes.

    Matplotlib names an SVG's clip paths and glyphs by hashes salted at random and stamps SVGs and PDFs with
    the time of writing; here the salt is fixed (``svg.hashsalt``) and the date left out.

    Args:
        fig: The figure.
        target: Output file or binary stream.
        fmt: The format.
        dpi: Resolution of the PNG (and of the rasters inside an SVG or PDF).
        **kwargs: More arguments of ``Figure.savefig`` (e.g. ``facecolor``).
    """
    if fmt in _NO_DATE:
        kwargs.setdefault("metadata", _NO_DATE[fmt])
    with mpl.rc_context({"svg.hashsalt": "amronet"}):
        fig.savefig(target, format=fmt, dpi=dpi, **kwargs)
