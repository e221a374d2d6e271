"""The signal layer: the best received signal strength (RSSI, dBm) per map cell, on one colour scale.

Every picture of a signal (``amronet radio-map``, ``snapshot --layer signal``, ``animate --layer signal``, the
replay page's signal layer) uses the same scale, fixed relative to the radio's usable threshold so that frames and
runs compare: ``viridis`` (perceptually uniform, readable in grey and by colour-blind readers) from
:data:`SPAN_DB` below the threshold to :data:`SPAN_DB` above it (stronger signals saturate; the colour bar's
upper end is an arrow). Cells more than :data:`SPAN_DB` below the threshold are left blank, as are walls and
unknown space. The threshold itself is a white line with a dark edge, visible on every colour of the scale: the
contour where the signal crosses it on the map (the border of the covered area), and a line with its value on the
colour bar.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numpy as np
from matplotlib import colormaps
from matplotlib import patheffects as pe
from matplotlib.axes import Axes
from matplotlib.cm import ScalarMappable
from matplotlib.colorbar import Colorbar
from matplotlib.colors import Colormap, Normalize
from matplotlib.contour import QuadContourSet
from matplotlib.figure import Figure
from matplotlib.image import AxesImage
from matplotlib.lines import Line2D
from matplotlib.patches import Patch

from amronet.viz.decorations import GAP, legend_patch
from amronet.world.occupancy import OccupancyMap

if TYPE_CHECKING:
    from amronet.outputs.recording import Recording

__all__ = [
    "CMAP",
    "COLORBAR_SPACE",
    "SPAN_DB",
    "SignalLayer",
    "add_signal_colorbar",
    "blank_handle",
    "coarse_grid",
    "draw_signal",
    "draw_threshold",
    "has_blank",
    "quantise",
    "signal_norm",
    "signal_rgba",
    "threshold_handle",
]

CMAP = "viridis"
"""The colour map of every signal picture."""

SPAN_DB = 30.0
"""The scale runs from this many dB below the usable threshold to as many above; weaker cells are blank."""

COLORBAR_SPACE = 1.0
"""Inches right of the map that the colour bar takes, gap and labels included (the legend goes right of it)."""

_BAR_WIDTH = 0.16
_LINE = {"color": "white", "linewidth": 1.3}
_EDGE = [pe.withStroke(linewidth=2.6, foreground="0.1")]


def signal_norm(threshold_dbm: float) -> Normalize:
    """The colour scale of a radio with usable threshold ``threshold_dbm``: threshold -/+ :data:`SPAN_DB`."""
    return Normalize(vmin=threshold_dbm - SPAN_DB, vmax=threshold_dbm + SPAN_DB, clip=True)


def _cmap() -> Colormap:
    return colormaps[CMAP]


def signal_rgba(signal: np.ndarray, threshold_dbm: float, shown: np.ndarray | None = None) -> np.ndarray:
    """The ``uint8`` RGBA image ``(rows, cols, 4)`` of a signal grid; transparent where NaN or not ``shown``."""
    signal = np.asarray(signal, dtype=float)
    valid = np.isfinite(signal) if shown is None else np.isfinite(signal) & shown
    rgba = _cmap()(signal_norm(threshold_dbm)(np.where(valid, signal, threshold_dbm)), bytes=True)
    rgba[..., 3] = np.where(valid, 255, 0)
    return rgba


def threshold_handle(threshold_dbm: float) -> Line2D:
    """Legend handle of the threshold contour."""
    return Line2D([], [], **_LINE, path_effects=_EDGE, label=f"usable threshold\n{threshold_dbm:.1f} dBm")


def blank_handle(threshold_dbm: float) -> Patch:
    """Legend handle of the blank cells: free, but more than :data:`SPAN_DB` below the threshold."""
    return legend_patch("white", f"free, below {threshold_dbm - SPAN_DB:.0f} dBm")


def has_blank(signal: np.ndarray, shown: np.ndarray | None = None) -> bool:
    """Whether some shown cell is blank (NaN)."""
    blank = ~np.isfinite(np.asarray(signal, dtype=float))
    return bool((blank if shown is None else blank & shown).any())


def draw_signal(ax: Axes, extent: tuple[float, float, float, float], signal: np.ndarray, threshold_dbm: float,
                shown: np.ndarray | None = None, *, zorder: float = 0.5) -> tuple[AxesImage, QuadContourSet | None]:
    """Draw a signal grid (row 0 at the bottom) over ``extent`` with its threshold contour.

    Args:
        ax: The map's axes (world metres).
        extent: ``(xmin, xmax, ymin, ymax)`` of the grid.
        signal: Best RSSI in dBm per cell, NaN where blank.
        threshold_dbm: The usable threshold: the contour's level.
        shown: Optional boolean mask of the cells to colour (e.g. the free cells); the others stay blank.
        zorder: Of the image (the contour goes just above it).

    Returns:
        The image and the contour (``None`` when the signal never crosses the threshold).
    """
    rgba = signal_rgba(signal, threshold_dbm, shown)
    image = ax.imshow(rgba, extent=extent, origin="lower", interpolation="nearest", zorder=zorder)
    contour = draw_threshold(ax, extent, signal, threshold_dbm, shown, zorder=zorder + 0.05)
    return image, contour


def draw_threshold(ax: Axes, extent: tuple[float, float, float, float], signal: np.ndarray, threshold_dbm: float,
                   shown: np.ndarray | None = None, *, zorder: float = 0.55) -> QuadContourSet | None:
    """The threshold contour of a signal grid (cell centres), or ``None`` if no cell pair crosses it."""
    signal = np.asarray(signal, dtype=float)
    valid = np.isfinite(signal) if shown is None else np.isfinite(signal) & shown
    if not ((signal[valid] >= threshold_dbm).any() and (signal[valid] < threshold_dbm).any()):
        return None
    rows, cols = signal.shape
    x0, x1, y0, y1 = extent
    xs = x0 + (np.arange(cols) + 0.5) * (x1 - x0) / cols
    ys = y0 + (np.arange(rows) + 0.5) * (y1 - y0) / rows
    z = np.ma.masked_array(np.where(valid, signal, threshold_dbm - SPAN_DB), mask=~valid)
    contour = ax.contour(xs, ys, z, levels=[threshold_dbm], colors=[_LINE["color"]],
                         linewidths=_LINE["linewidth"], linestyles="solid", zorder=zorder)
    contour.set_path_effects(_EDGE)
    return contour


def _ticks(threshold_dbm: float) -> list[float]:
    """Round ticks every 10 dB on the scale, less those that would crowd the threshold's own tick."""
    lo, hi = threshold_dbm - SPAN_DB, threshold_dbm + SPAN_DB
    ticks = [10.0 * k for k in range(math.ceil(lo / 10), math.floor(hi / 10) + 1)]
    return sorted([t for t in ticks if abs(t - threshold_dbm) >= 4.0] + [threshold_dbm])


def add_signal_colorbar(fig: Figure, ax: Axes, threshold_dbm: float) -> Colorbar:
    """The colour bar of the signal scale, right of the map's axes, as tall as the map, the threshold marked.

    It takes :data:`COLORBAR_SPACE` inches; place the legend that far right of the axes.
    """
    _, y0, x1, y1 = ax.get_position().extents
    fig_w = fig.get_figwidth()
    cax = fig.add_axes((x1 + GAP / fig_w, y0, _BAR_WIDTH / fig_w, y1 - y0))
    bar = fig.colorbar(ScalarMappable(norm=signal_norm(threshold_dbm), cmap=_cmap()), cax=cax, extend="max")
    bar.set_label("best RSSI [dBm]", fontsize=8)
    ticks = _ticks(threshold_dbm)
    bar.set_ticks(ticks)
    bar.set_ticklabels([f"{t:.1f}" if t == threshold_dbm else f"{t:g}" for t in ticks])
    bar.ax.tick_params(labelsize=7.5)
    for label, t in zip(bar.ax.get_yticklabels(), ticks, strict=True):
        if t == threshold_dbm:
            label.set_fontweight("bold")
    bar.ax.axhline(threshold_dbm, **_LINE, path_effects=_EDGE)
    return bar


def quantise(signal: np.ndarray, threshold_dbm: float, first: int = 2) -> np.ndarray:
    """``uint8`` codes of a signal grid on the colour scale: 0 blank, ``first``..255 from its bottom to its top.

    The scale is cut into ``256 - first`` equal bins (code ``first`` holds the bottom one and everything weaker
    that is not blank, 255 the top one and everything stronger). With ``first`` even the threshold is a bin edge:
    a cell's signal reaches the threshold exactly when its code is at least ``first + (256 - first) // 2``.
    """
    signal = np.asarray(signal, dtype=float)
    valid = np.isfinite(signal)
    lo, bins = threshold_dbm - SPAN_DB, 256 - first
    code = first + np.floor((np.where(valid, signal, lo) - lo) / (2 * SPAN_DB) * bins)
    return np.where(valid, np.clip(code, first, 255), 0).astype(np.uint8)


def coarse_grid(omap: OccupancyMap, max_side: int) -> tuple[OccupancyMap, int]:
    """A grid over ``omap`` with at most ``max_side`` cells a side: ``k x k`` cells merged (``k >= 1``).

    The coarse grid starts at the map's origin and holds ``rows // k`` by ``cols // k`` cells (so it may stop up
    to ``k - 1`` cells short of the map's top and right edges); a coarse cell takes the category of the map's
    cell at its centre.

    Returns:
        The grid (an :class:`OccupancyMap`, to evaluate signals at its cell centres) and ``k``.
    """
    rows, cols = omap.shape
    k = max(1, math.ceil(max(rows, cols) / max_side))
    if k == 1:
        return omap, 1
    r, c = max(rows // k, 1), max(cols // k, 1)
    centre_r = np.minimum(np.arange(r) * k + k // 2, rows - 1)
    centre_c = np.minimum(np.arange(c) * k + k // 2, cols - 1)
    cells = np.ascontiguousarray(omap.cells[np.ix_(centre_r, centre_c)])
    return OccupancyMap(omap.name, omap.resolution * k, omap.origin, cells), k


_SIGNAL_PIXELS = 2.0
"""An animation's signal grid has cells of at least this many pixels a side (a signal map costs per cell)."""


class SignalLayer:
    """The signal of a recording's frames on an animation's axes: an image and the threshold contour.

    The signal is evaluated on a grid with cells of at least :data:`_SIGNAL_PIXELS` pixels a side
    (:func:`coarse_grid`), and again only when the routers and base nodes moved since the last
    frame drawn.
    """

    def __init__(self, rec: Recording, ax: Axes, threshold: float) -> None:
        self.rec, self.ax, self.threshold = rec, ax, threshold
        box = ax.get_window_extent()
        self.grid, self.k = coarse_grid(rec.omap, max(round(max(box.width, box.height) / _SIGNAL_PIXELS), 1))
        x0, _, y0, _ = rec.omap.extent
        rows, cols = self.grid.shape
        self.extent = (x0, x0 + cols * self.grid.resolution, y0, y0 + rows * self.grid.resolution)
        self.counted = rec.omap.free & rec.reachable
        centre_r = np.minimum(np.arange(rows) * self.k + self.k // 2, rec.omap.shape[0] - 1)
        centre_c = np.minimum(np.arange(cols) * self.k + self.k // 2, rec.omap.shape[1] - 1)
        self.shown = self.counted[np.ix_(centre_r, centre_c)]
        limits = ax.get_xlim(), ax.get_ylim()
        # the image has the map's cells (the coarse values repeated), so that walls keep their exact shape
        self.image = ax.imshow(np.zeros((*rec.omap.shape, 4), np.uint8), extent=rec.omap.extent, origin="lower",
                               interpolation="antialiased", zorder=0.5)
        ax.set_xlim(*limits[0])
        ax.set_ylim(*limits[1])
        self.contour = None
        self._key: bytes | None = None

    def update(self, f: int) -> None:
        """Show frame ``f``'s signal (evaluated again only when the routers and base nodes moved)."""
        xy = np.ascontiguousarray(self.rec.network_xy(f))
        key = xy.tobytes()
        if key == self._key:
            return
        self._key = key
        signal = self.rec.signal(f, grid=self.grid, floor_db=-SPAN_DB)
        rows, cols = self.rec.omap.shape
        fine = np.repeat(np.repeat(signal, self.k, axis=0), self.k, axis=1)
        fine = np.pad(fine, ((0, rows - fine.shape[0]), (0, cols - fine.shape[1])), mode="edge")
        self.image.set_data(signal_rgba(fine, self.threshold, self.counted))
        if self.contour is not None:
            self.contour.remove()
        self.contour = draw_threshold(self.ax, self.extent, signal, self.threshold, self.shown)
        if self.contour is not None:
            self.contour.set_animated(True)
