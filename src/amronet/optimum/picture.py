"""The picture of an optimum: the map to scale, the area the placement covers, its links, routers and base stations.

matplotlib is imported here only, and this module only when a picture is drawn (Agg canvas, never ``pyplot``).
"""

from __future__ import annotations

import io

import numpy as np

from amronet.engine.coverage import CoverageArea
from amronet.optimum.report import Optimum

__all__ = ["optimum_png"]

_COVERED = (0.12, 0.31, 0.6, 0.16)
_LINK = (0.25, 0.25, 0.25, 0.8)
_ROUTER = "#1f4e9a"
_BASE = "#111111"
_SITE = (0.55, 0.55, 0.55, 0.6)


def optimum_png(opt: Optimum, dpi: float = 120) -> bytes:
    """PNG of the best placement: covered area tinted, uncovered reachable cells light red, links, nodes, sites."""
    from matplotlib.collections import LineCollection

    from amronet.viz.decorations import add_legend, legend_patch, marker_handle, save_figure
    from amronet.viz.maps import draw_map, map_patch, new_map_figure

    inst = opt.instance
    if inst is None:
        raise ValueError("the optimum carries no instance to draw")
    omap = inst.omap
    xy = np.vstack([inst.bases_xy, opt.routers])
    covered = inst.medium.covered_mask(CoverageArea(omap, inst.reachable), xy)
    fig, ax = new_map_figure(omap, right=2.7, dpi=dpi)
    draw_map(ax, omap, reachable=inst.reachable, covered=covered)
    tint = np.zeros((*omap.shape, 4))
    tint[covered] = _COVERED
    ax.imshow(tint, extent=omap.extent, origin="lower", interpolation="nearest", zorder=0.5)
    ax.scatter(*inst.sites.T, s=1.5, c=[_SITE], linewidths=0, zorder=1)
    table = inst.medium.update(xy)
    rows = np.repeat(np.arange(len(xy)), np.diff(table.indptr))
    upper = table.indices > rows
    if upper.any():
        segs = np.stack([xy[rows[upper]], xy[table.indices[upper]]], axis=1)
        ax.add_collection(LineCollection(segs, colors=[_LINK], linewidths=0.7, zorder=2))
    if len(opt.routers):
        ax.scatter(*opt.routers.T, s=16, c=_ROUTER, edgecolors="white", linewidths=0.4, zorder=4)
    ax.scatter(*inst.bases_xy.T, s=40, marker="s", c=_BASE, edgecolors="white", linewidths=0.6, zorder=5)
    gap = opt.gap
    state = "optimal" if opt.optimal else ("gap unbounded" if gap is None else f"gap {100 * gap:.1f} %")
    model = opt.radio["model"]
    ax.set_title(f"{omap.name}: {opt.count} routers, proven bound {opt.lower} ({state})\n"
                 f"r_c = {opt.radio['r_c']:g} m, {model}, candidates every {opt.spacing:g} m", fontsize=9)
    handles = [marker_handle("s", 6, _BASE, "base station (counts 0)"),
               marker_handle("o", 5, _ROUTER, f"router ({opt.count})", edge="white"),
               marker_handle(".", 4, _SITE, "candidate site", edge=_SITE),
               legend_patch(_LINK, "link"), legend_patch(_COVERED, "covered"), map_patch("uncovered"),
               map_patch("unreachable"), map_patch("occupied")]
    add_legend(fig, ax, handles)
    buf = io.BytesIO()
    save_figure(fig, buf, "png", dpi, facecolor="white")
    return buf.getvalue()
