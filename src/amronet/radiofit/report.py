"""A radio fit as ``fit.json`` (a plain dict) and as the lines the command prints."""

from __future__ import annotations

import numpy as np

from amronet.radiofit.emit import radio_block, set_lines
from amronet.radiofit.fit import ModelFit, RadioFit

__all__ = ["CANNOT_DETERMINE", "fit_dict", "fit_text"]

CANNOT_DETERMINE = (
    "tx_dbm and pl0_db separately: only their difference A = tx_dbm - pl0_db (the RSSI at 1 m) enters the law; "
    "radio.yaml keeps pl0_db = 40 dB and sets tx_dbm = A + 40",
    "the path-loss exponent and the wall loss independently of each other: longer links cross more walls, so the "
    "two trade off (see correlation_exponent_wall)",
    "which walls are heavy: one loss for every wall of the map (material and thickness are not in it), and "
    "furniture, which is not in the map, ends up in the exponent and the shadowing",
    "a radio's own threshold: the readings stop at the receivers' floor, which radio.yaml gives as threshold_dbm",
)


def _interval(samples: np.ndarray) -> list[float]:
    ok = samples[np.isfinite(samples)]
    return [float(v) for v in np.percentile(ok, [2.5, 97.5])] if len(ok) else [float("nan")] * 2


def _param(value: float, samples: np.ndarray) -> dict:
    ok = samples[np.isfinite(samples)]
    return {"value": float(value), "se": float(np.std(ok, ddof=1)) if len(ok) > 1 else float("nan"),
            "ci95": _interval(samples)}


def _cv(f: ModelFit) -> dict:
    """Cross-validated RMSE and mean error: over blocks of positions (the headline) and over single positions."""
    return {"cv_rmse_db": f.cv_rmse, "cv_mean_error_db": f.cv_mean_error, "cv_position_rmse_db": f.cv_position_rmse,
            "cv_position_mean_error_db": f.cv_position_mean_error}


def model_dict(f: ModelFit) -> dict:
    """The detailed fit of one model."""
    params = {n: _param(v, f.boot[:, j]) for j, (n, v) in enumerate(zip(f.names, f.coef, strict=True))}
    params["shadowing_db"] = _param(f.sigma, f.boot_sigma)
    nug, sill, corr = f.gudmundson
    params["shadowing_corr_m"] = _param(corr, f.boot_gudmundson[:, 2])
    out = {"model": f.model.model, "per_anchor": f.model.per_anchor, "parameters": params,
           "rmse_db": f.rmse, **_cv(f), "cv_fold_rmse_db": f.cv_fold_rmse.tolist(),
           "variogram": {"lag_m": f.variogram.lag.tolist(), "gamma_db2": f.variogram.gamma.tolist(),
                         "pairs": f.variogram.pairs.astype(int).tolist(),
                         "gudmundson": {"nugget_db2": _param(nug, f.boot_gudmundson[:, 0]),
                                        "sill_db2": _param(sill, f.boot_gudmundson[:, 1]),
                                        "corr_m": _param(corr, f.boot_gudmundson[:, 2])}},
           "censoring": f.censoring}
    if "wall_db" in f.names:
        j, k = f.names.index("path_loss_exponent"), f.names.index("wall_db")
        out["correlation_exponent_wall"] = float(np.corrcoef(f.boot[:, j], f.boot[:, k])[0, 1])
    if f.held:
        out["held_at_bounds"] = {"parameters": f.held,
                                 "coef": dict(zip(f.names, f.held_coef.tolist(), strict=True))}
    return out


def fit_dict(rf: RadioFit, data: dict) -> dict:
    """``fit.json``: the data, the options, the comparison table, the detailed fits and the emitted block."""
    r, o = rf.readings, rf.options
    block = radio_block(rf.best, r, rf.floor_dbm)
    return {
        "data": {**data, "readings": len(r.rssi), "positions": r.n_spots, "anchors": r.anchor_ids.tolist(),
                 "tag_height_m": r.tag_height, "missing_links": int(len(r.cens_spot))},
        "options": {"models": list(o.models), "per_anchor": o.per_anchor, "bootstrap": o.n_boot,
                    "folds": o.folds, "seed": o.seed, "floor_dbm": rf.floor_dbm, "max_lag_m": o.max_lag,
                    "block_m": o.block_m},
        "cross_validation": {"folds": o.folds, "block_m": rf.block_m, "blocks": rf.n_blocks,
                             "block_rule": rf.block_rule,
                             "headline": "cv_rmse_db: folds of square blocks of positions; cv_position_rmse_db: "
                                         "folds of single positions"},
        "comparison": [{"model": t.model.label, "coef": dict(zip(t.names, t.coef.tolist(), strict=True)),
                        "rmse_db": t.rmse, **_cv(t), "sigma_db": t.sigma} for t in rf.table],
        "fits": [model_dict(f) for f in rf.fits],
        "chosen": rf.best.model.label,
        "radio": block,
        "cannot_determine": list(CANNOT_DETERMINE),
    }


def _blocks_text(rf: RadioFit) -> str:
    if rf.block_m == 0.0:
        return f"single positions ({rf.block_rule})"
    return f"{rf.n_blocks} blocks of {rf.block_m:g} x {rf.block_m:g} m ({rf.block_rule})"


def fit_text(rf: RadioFit) -> str:
    """What the command prints: the comparison, the chosen fit with intervals, the block as ``--set`` lines."""
    r = rf.readings
    lines = [f"{len(r.rssi)} readings at {r.n_spots} positions from {r.n_anchors} anchors "
             f"({len(r.cens_spot)} (point, anchor) pairs not heard)",
             f"{rf.options.folds}-fold cross-validation (CV) over {_blocks_text(rf)}, and over single positions (pos.)",
             f"{'model':<28}{'RMSE':>8}{'CV RMSE':>9}{'CV mean':>9}{'pos. RMSE':>10}  A [dBm]  n      wall [dB]"]
    for t in rf.table:
        c = dict(zip(t.names, t.coef, strict=True))
        a = np.mean([v for k, v in c.items() if k.startswith("a_dbm")])
        wall = f"{c['wall_db']:.2f}" if "wall_db" in c else "-"
        lines.append(f"{t.model.label:<28}{t.rmse:8.2f}{t.cv_rmse:9.2f}{t.cv_mean_error:+9.2f}"
                     f"{t.cv_position_rmse:10.2f}  {a:7.2f}  "
                     f"{c['path_loss_exponent']:.3f}  {wall}")
    for f in rf.fits:
        d = model_dict(f)
        lines.append(f"{f.model.label}: parameter, 95 % bootstrap interval ({len(f.boot)} resamples over positions)")
        for name, p in d["parameters"].items():
            lo, hi = p["ci95"]
            lines.append(f"  {name:<22}{p['value']:9.3f}  [{lo:.3f}, {hi:.3f}]")
        if "correlation_exponent_wall" in d:
            lines.append(f"  exponent-wall correlation {d['correlation_exponent_wall']:+.2f}")
        for name, value in f.held.items():
            lines.append(f"  {name} {f.coef[f.names.index(name)]:.3f} is outside amronet's bounds: radio.yaml holds "
                         f"it at {value:g} and refits the rest")
        cz = f.censoring
        if "tobit" in cz:
            lines.append(f"  floor {cz['floor_dbm']:g} dBm: missing links' predicted median "
                         f"{cz['missing_predicted_median_dbm']:.1f} dBm (missing for other reasons than the floor "
                         "when far above it)")
        tr = cz["truncated"]["coef"]
        lines.append("  truncated fit (floor): " + ", ".join(f"{k} {v:.3f}" for k, v in tr.items()))
    lines.append(f"radio.yaml ({rf.best.model.label}, lowest CV RMSE of the fitted):")
    lines.extend("  " + s for s in set_lines(radio_block(rf.best, r, rf.floor_dbm)))
    return "\n".join(lines) + "\n"
