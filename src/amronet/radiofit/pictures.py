"""Pictures of a radio fit: how well it predicts, where it errs, how the residuals are correlated.

matplotlib is imported here only, and this module only when pictures are drawn (Agg canvas, never ``pyplot``).
"""

from __future__ import annotations

import io

import numpy as np

from amronet.radiofit.fit import ModelFit, RadioFit
from amronet.radiofit.variogram import gudmundson
from amronet.world.occupancy import OccupancyMap

__all__ = ["fit_png", "residual_map_png"]


def _png(fig: object, dpi: float) -> bytes:
    from amronet.viz.decorations import save_figure

    buf = io.BytesIO()
    save_figure(fig, buf, "png", dpi)
    return buf.getvalue()


def fit_png(rf: RadioFit, fit: ModelFit, dpi: float = 110) -> bytes:
    """Four panels: measured vs predicted, residuals vs distance, residuals vs walls, the variogram with its fit."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    r = rf.readings
    pred = fit.predict(r)
    resid = r.rssi - pred
    fig = Figure(figsize=(11, 8.5), facecolor="white")
    FigureCanvasAgg(fig)
    ax = fig.subplots(2, 2)
    hb = ax[0, 0].hexbin(pred, r.rssi, gridsize=45, mincnt=1, bins="log", cmap="viridis")
    lo, hi = min(pred.min(), r.rssi.min()), max(pred.max(), r.rssi.max())
    ax[0, 0].plot([lo, hi], [lo, hi], color="crimson", lw=1)
    ax[0, 0].set(xlabel="predicted RSSI [dBm]", ylabel="measured RSSI [dBm]",
                 title=f"{fit.model.label}: RMSE {fit.rmse:.2f} dB, CV {fit.cv_rmse:.2f} dB")
    fig.colorbar(hb, ax=ax[0, 0], label="readings")
    ax[0, 1].hexbin(r.d, resid, gridsize=45, mincnt=1, bins="log", cmap="viridis", xscale="log")
    edges = np.geomspace(r.d.min(), r.d.max() * 1.0001, 12)
    k = np.digitize(r.d, edges) - 1
    mids = np.sqrt(edges[:-1] * edges[1:])
    means = np.array([resid[k == i].mean() if np.any(k == i) else np.nan for i in range(len(mids))])
    ax[0, 1].plot(mids, means, "o-", color="crimson", label="mean per bin")
    ax[0, 1].axhline(0, color="0.3", lw=0.8)
    ax[0, 1].set(xlabel="3-D distance [m] (log)", ylabel="measured - predicted [dB]", title="residuals vs distance")
    ax[0, 1].legend(loc="lower left")
    walls = r.walls.astype(int)
    levels = np.unique(walls)
    ax[1, 0].boxplot([resid[walls == w] for w in levels], positions=levels, widths=0.6, showfliers=False)
    ax[1, 0].axhline(0, color="0.3", lw=0.8)
    ax[1, 0].set_xticks(levels, [f"{w}\n({np.sum(walls == w)})" for w in levels])
    ax[1, 0].set(xlabel="walls crossed (readings)", ylabel="measured - predicted [dB]", title="residuals vs walls")
    v = fit.variogram
    ok = v.pairs > 0
    ax[1, 1].plot(v.lag[ok], v.gamma[ok], "o", ms=4, label="empirical (same anchor)")
    nug, sill, corr = fit.gudmundson
    if np.isfinite(corr):
        h = np.linspace(1e-3, v.edges[-1], 200)
        ax[1, 1].plot(h, gudmundson(h, nug, sill, corr), color="crimson",
                      label=f"nugget {nug:.1f} + {sill:.1f}(1 - exp(-h/{corr:.2f} m))")
    ax[1, 1].axhline(fit.sigma**2, color="0.5", ls="--", lw=0.8, label=f"residual variance {fit.sigma**2:.1f}")
    ax[1, 1].set(xlabel="lag between tag positions [m]", ylabel="semivariance [dB²]", ylim=(0, None),
                 title="variogram of residuals, Gudmundson fit")
    ax[1, 1].legend(loc="lower right", fontsize=8)
    fig.tight_layout()
    return _png(fig, dpi)


def residual_map_png(rf: RadioFit, fit: ModelFit, omap: OccupancyMap, dpi: float = 110) -> bytes:
    """The map with each position's mean residual over its readings (all anchors) and the anchors."""
    from amronet.viz.maps import draw_map, new_map_figure

    r = rf.readings
    resid = r.rssi - fit.predict(r)
    n = np.bincount(r.spot, minlength=r.n_spots)
    mean = np.bincount(r.spot, weights=resid, minlength=r.n_spots) / np.maximum(n, 1)
    fig, ax = new_map_figure(omap, 1.6, dpi)
    draw_map(ax, omap)
    lim = float(np.percentile(np.abs(mean), 98))
    sc = ax.scatter(r.spot_xy[:, 0], r.spot_xy[:, 1], c=mean, s=6, cmap="RdBu", vmin=-lim, vmax=lim, zorder=2)
    ax.scatter(r.anchor_xyz[:, 0], r.anchor_xyz[:, 1], marker="^", s=80, c="k", zorder=3)
    for i, (x, y, _) in zip(r.anchor_ids, r.anchor_xyz, strict=True):
        ax.annotate(str(i), (x, y), xytext=(4, 4), textcoords="offset points", fontsize=9, zorder=4)
    fig.colorbar(sc, ax=ax, label="mean residual [dB] (measured - predicted)")
    ax.set_title(f"{fit.model.label}: residual per position, anchors ▲", fontsize=10)
    return _png(fig, dpi)
