"""Fitting a radio model to readings: coefficients, bootstrap intervals, cross-validation, shadowing, censoring.

:func:`fit_radio` fits the chosen models (:mod:`amronet.radiofit.linear`) by least squares on the heard readings,
then for each:

* the uncertainty of every parameter by a bootstrap over spots (seeded; readings of one spot stay together);
* RMSE and mean error by k-fold cross-validation (the same folds for every model), twice: over square *blocks* of
  spots (the headline: a held-out spot's correlated neighbours are held out with it, see :func:`block_size`) and
  over single spots;
* the residuals' spread (``shadowing_db``) and their decorrelation distance (``shadowing_corr_m``, from the
  variogram, :mod:`amronet.radiofit.variogram`);
* what the receiver's floor changes (:mod:`amronet.radiofit.tobit`);
* the parameters a scenario can take: a value outside amronet's bounds
  (:data:`~amronet.engine.propagation.RADIO_BOUNDS`) is held at the bound and the rest fitted again.

One generator drives everything: the same seed gives the same result bit for bit.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from amronet.engine.propagation import RADIO_BOUNDS
from amronet.radiofit.data import RadioFitError, Readings
from amronet.radiofit.linear import (
    MODELS,
    LinearModel,
    block_of_spots,
    design,
    fit_weighted,
    fold_of_blocks,
    fold_of_spots,
    spot_weights,
)
from amronet.radiofit.tobit import fit_censored, fit_tobit
from amronet.radiofit.variogram import CORR_BOUNDS_M, Variogram, empirical_variogram, fit_gudmundson

__all__ = ["BLOCK_CORR_LENGTHS", "FitOptions", "ModelFit", "RadioFit", "block_size", "fit_radio"]

BLOCK_CORR_LENGTHS = 3.0
"""The blocks' side by default, in correlation distances of the multi-wall residuals: at 3 of them Gudmundson's
correlation ``exp(-h / d_corr)`` has fallen to 5 %."""


@dataclass(frozen=True)
class FitOptions:
    """What to fit and how.

    Attributes:
        models: The models fitted in detail (bootstrap, variogram, censoring).
        per_anchor: One constant per anchor in the detailed fits.
        n_boot: Bootstrap resamples.
        folds: Cross-validation folds.
        block_m: Side of the square blocks of spots that cross-validation holds out together (m); ``None``:
            :data:`BLOCK_CORR_LENGTHS` correlation distances of the multi-wall fit's residuals (see
            :func:`block_size`).
        seed: Seed of the folds and the bootstrap.
        floor_dbm: The receivers' floor (dBm); ``None``: the weakest reading.
        max_lag: Longest lag of the variogram (m).
    """

    models: tuple[str, ...] = ("multi-wall",)
    per_anchor: bool = False
    n_boot: int = 200
    folds: int = 5
    seed: int = 0
    floor_dbm: float | None = None
    max_lag: float = 3.0
    block_m: float | None = None


@dataclass
class ModelFit:
    """One model fitted to the readings (see the module doc)."""

    model: LinearModel
    names: list[str]
    coef: np.ndarray
    sigma: float
    rmse: float
    cv_rmse: float = float("nan")
    """Cross-validated RMSE over blocks of spots (the headline)."""
    cv_mean_error: float = float("nan")
    """Cross-validated mean error (measured minus predicted) over blocks of spots."""
    cv_fold_rmse: np.ndarray = field(default_factory=lambda: np.zeros(0))
    """RMSE of each fold of blocks."""
    cv_position_rmse: float = float("nan")
    """Cross-validated RMSE over single spots."""
    cv_position_mean_error: float = float("nan")
    """Cross-validated mean error over single spots."""
    boot: np.ndarray = field(default_factory=lambda: np.zeros((0, 0)))
    """Bootstrap coefficients ``(B, p)``."""
    boot_sigma: np.ndarray = field(default_factory=lambda: np.zeros(0))
    variogram: Variogram | None = None
    gudmundson: tuple[float, float, float] = (float("nan"),) * 3
    """``(nugget, sill, corr_m)`` of the variogram's fit."""
    boot_gudmundson: np.ndarray = field(default_factory=lambda: np.zeros((0, 3)))
    censoring: dict = field(default_factory=dict)
    held: dict = field(default_factory=dict)
    """Parameters held at amronet's bounds: name -> value (empty when the fit is within them)."""
    held_coef: np.ndarray | None = None
    """The coefficients with ``held`` applied (all columns), or ``None`` when nothing is held."""

    def predict(self, r: Readings, coef: np.ndarray | None = None) -> np.ndarray:
        """Mean RSSI (dBm) of every reading of ``r`` under ``coef`` (default: the fit)."""
        return design(self.model, r.anchor, r.d, r.walls, r.n_anchors) @ (self.coef if coef is None else coef)

    @property
    def scenario_coef(self) -> np.ndarray:
        """The coefficients a scenario gets: the fit, or with values outside amronet's bounds held at them."""
        return self.coef if self.held_coef is None else self.held_coef


@dataclass
class RadioFit:
    """All fits of one data set: a comparison table and the detailed fits."""

    readings: Readings
    options: FitOptions
    floor_dbm: float
    table: list[ModelFit]
    fits: list[ModelFit]
    best: ModelFit
    block_m: float
    """Side of the cross-validation's blocks (m); 0: each spot is its own block."""
    n_blocks: int
    """Blocks that hold spots."""
    block_rule: str
    """How ``block_m`` was chosen, in words."""


def _cross_validate(x: np.ndarray, y: np.ndarray, spot: np.ndarray, fold: np.ndarray, k: int
                    ) -> tuple[float, float, np.ndarray]:
    """Held-out RMSE, mean error (measured minus predicted) and RMSE per fold."""
    err = np.empty(len(y))
    fold_r = fold[spot]
    for f in range(k):
        test = fold_r == f
        coef, *_ = np.linalg.lstsq(x[~test], y[~test], rcond=None)
        err[test] = y[test] - x[test] @ coef
    per_fold = np.array([np.sqrt(np.mean(err[fold_r == f] ** 2)) for f in range(k)])
    return float(np.sqrt(np.mean(err**2))), float(np.mean(err)), per_fold


def _basic(r: Readings, m: LinearModel) -> ModelFit:
    x = design(m, r.anchor, r.d, r.walls, r.n_anchors)
    coef, *_ = np.linalg.lstsq(x, r.rssi, rcond=None)
    resid = r.rssi - x @ coef
    rmse = float(np.sqrt(np.mean(resid**2)))
    sigma = float(np.sqrt(np.sum(resid**2) / (len(resid) - x.shape[1])))
    return ModelFit(m, m.names(r.anchor_ids), coef, sigma, rmse)


def _validate(r: Readings, fit: ModelFit, block_fold: np.ndarray, spot_fold: np.ndarray, k: int) -> None:
    x = design(fit.model, r.anchor, r.d, r.walls, r.n_anchors)
    fit.cv_rmse, fit.cv_mean_error, fit.cv_fold_rmse = _cross_validate(x, r.rssi, r.spot, block_fold, k)
    fit.cv_position_rmse, fit.cv_position_mean_error, _ = _cross_validate(x, r.rssi, r.spot, spot_fold, k)


def _variogram(r: Readings, fit: ModelFit, max_lag: float) -> None:
    """The residuals' variogram and its Gudmundson fit, into ``fit``."""
    resid = r.rssi - fit.predict(r)
    fit.variogram = empirical_variogram(r.spot_xy, r.spot, r.anchor, resid, max_lag=max_lag)
    fit.gudmundson = fit_gudmundson(fit.variogram.lag, fit.variogram.gamma, fit.variogram.pairs)


def block_size(spot_xy: np.ndarray, corr_m: float, k: int, given: float | None = None
               ) -> tuple[float, np.ndarray, str]:
    """The side of the cross-validation's blocks, each spot's block, and how the side was chosen.

    Readings at spots closer than the residuals' correlation distance share their shadowing, so a spot held out
    while its neighbours stay in the training folds is predicted with help the model will not have at a new
    place. Blocks hold neighbours out together. Given ``given``, blocks of that side; else
    :data:`BLOCK_CORR_LENGTHS` times ``corr_m`` (rounded to 1 cm), shrunk by factors of 0.8 until there are at
    least ``2 k`` blocks; when the residuals show no correlation (``corr_m`` not finite, or at the lower bound of
    the variogram's fit), or when even blocks of 1 cm are fewer than ``2 k``, each spot is its own block (side 0).

    Raises:
        RadioFitError: ``given`` leaves fewer than ``2 k`` blocks.
    """
    if given is not None:
        block = block_of_spots(spot_xy, given)
        n = int(block.max()) + 1
        if n < 2 * k:
            raise RadioFitError(f"--block-m: blocks of {given:g} m hold the positions in {n} blocks, too few for "
                                f"{k}-fold cross-validation (at least {2 * k}); give a smaller --block-m or fewer "
                                "--folds")
        return float(given), block, "given (--block-m)"
    if not np.isfinite(corr_m) or corr_m <= 1.01 * CORR_BOUNDS_M[0]:
        return 0.0, np.arange(len(spot_xy)), "no spatial correlation in the residuals: each position is its own block"
    side = round(BLOCK_CORR_LENGTHS * float(corr_m), 2)
    rule = f"{BLOCK_CORR_LENGTHS:g} x the multi-wall residuals' correlation distance ({corr_m:.2f} m)"
    block = block_of_spots(spot_xy, side)
    shrunk = False
    while int(block.max()) + 1 < 2 * k:
        if round(0.8 * side, 2) in (side, 0.0):  # 1 cm shrinks no further: the positions lie closer than that
            return 0.0, np.arange(len(spot_xy)), (f"the positions leave fewer than {2 * k} blocks even of 1 cm: "
                                                  "each position is its own block")
        side, shrunk = round(0.8 * side, 2), True
        block = block_of_spots(spot_xy, side)
    if shrunk:
        rule += f", shrunk to give at least {2 * k} blocks"
    return side, block, rule


def _hold_at_bounds(r: Readings, fit: ModelFit) -> None:
    """Hold the exponent and wall loss at amronet's bounds when the fit is outside them; refit the rest."""
    x = design(fit.model, r.anchor, r.d, r.walls, r.n_anchors)
    coef = fit.coef.copy()
    held: dict[str, float] = {}
    for _ in range(2):  # holding one may push the other out
        free = np.ones(len(coef), bool)
        for name, value in held.items():
            free[fit.names.index(name)] = False
            coef[fit.names.index(name)] = value
        y = r.rssi - x[:, ~free] @ coef[~free]
        coef[free], *_ = np.linalg.lstsq(x[:, free], y, rcond=None)
        changed = False
        for name in ("path_loss_exponent", "wall_db"):
            if name in fit.names and name not in held:
                b, v = RADIO_BOUNDS[name], coef[fit.names.index(name)]
                if not b.lo <= v <= b.hi:
                    held[name] = float(np.clip(v, b.lo, b.hi))
                    changed = True
        if not changed:
            break
    if held:
        fit.held, fit.held_coef = held, coef


def _censoring(r: Readings, fit: ModelFit, floor: float) -> dict:
    """What the floor changes: the truncated and the Tobit fits, and whether missing readings look censored."""
    x = design(fit.model, r.anchor, r.d, r.walls, r.n_anchors)
    out: dict = {"floor_dbm": floor, "readings_within_3db_of_floor": int(np.sum(r.rssi < floor + 3.0))}
    coef, sigma = fit_censored(x, r.rssi, floor, fit.coef)
    out["truncated"] = {"coef": dict(zip(fit.names, coef.tolist(), strict=True)), "sigma_db": sigma}
    if len(r.cens_spot):
        xc = design(fit.model, r.cens_anchor, r.cens_d, r.cens_walls, r.n_anchors)
        coef, sigma = fit_tobit(x, r.rssi, xc, floor, fit.coef)
        mu_c = xc @ fit.coef
        out["tobit"] = {"coef": dict(zip(fit.names, coef.tolist(), strict=True)), "sigma_db": sigma}
        out["missing_links"] = int(len(r.cens_spot))
        out["missing_predicted_median_dbm"] = float(np.median(mu_c))
        out["missing_rate_by_walls"] = {
            str(w): float(np.sum(r.cens_walls == w) / max(np.sum(r.walls == w) + np.sum(r.cens_walls == w), 1))
            for w in np.unique(np.concatenate([r.walls, r.cens_walls])).astype(int)}
    return out


def _detail(r: Readings, fit: ModelFit, weights: np.ndarray, floor: float, max_lag: float) -> None:
    x = design(fit.model, r.anchor, r.d, r.walls, r.n_anchors)
    w = weights[:, r.spot]
    fit.boot = fit_weighted(x, r.rssi, w)
    resid_b = r.rssi[None, :] - fit.boot @ x.T
    fit.boot_sigma = np.sqrt(np.sum(w * resid_b**2, axis=1) / np.sum(w, axis=1))
    if fit.variogram is None:
        _variogram(r, fit, max_lag)
    lag, gamma, n = fit.variogram.resampled(weights)
    fit.boot_gudmundson = np.array([fit_gudmundson(lag[b], gamma[b], n[b]) for b in range(len(weights))])
    fit.censoring = _censoring(r, fit, floor)
    _hold_at_bounds(r, fit)


def fit_radio(r: Readings, opt: FitOptions) -> RadioFit:
    """Fit the comparison table and the detailed models of ``opt`` to the readings ``r`` (see the module doc).

    Raises:
        RadioFitError: ``opt.floor_dbm`` is above a reading, or the positions are too few for the folds.
    """
    weakest = float(np.min(r.rssi))
    if opt.floor_dbm is not None and opt.floor_dbm > weakest:
        below = int(np.sum(r.rssi < opt.floor_dbm))
        raise RadioFitError(f"--floor-dbm: {opt.floor_dbm:g} dBm is above {below} of the {len(r.rssi)} readings (the "
                            f"weakest is {weakest:g} dBm), but receivers report nothing below their floor; give "
                            f"{weakest:g} or lower, or leave it out")
    if r.n_spots < 2 * opt.folds:
        raise RadioFitError(f"--rssi: {r.n_spots} distinct positions are too few for {opt.folds}-fold "
                            "cross-validation; give more positions or fewer --folds")
    fold_rng, boot_rng, block_rng = np.random.default_rng(opt.seed).spawn(3)
    spot_fold = fold_of_spots(fold_rng, r.n_spots, opt.folds)
    weights = spot_weights(boot_rng, r.n_spots, opt.n_boot)
    floor = weakest if opt.floor_dbm is None else float(opt.floor_dbm)
    table = [_basic(r, LinearModel(m, pa)) for pa in (False, True) for m in MODELS]
    corr = float("nan")
    if opt.block_m is None:  # the blocks' side from the multi-wall residuals' correlation distance
        walls = next(t for t in table if t.model == LinearModel("multi-wall"))
        _variogram(r, walls, opt.max_lag)
        corr = walls.gudmundson[2]
    side, block, rule = block_size(r.spot_xy, corr, opt.folds, opt.block_m)
    block_fold = fold_of_blocks(block_rng, block, opt.folds)
    for t in table:
        _validate(r, t, block_fold, spot_fold, opt.folds)
    fits = []
    for name in opt.models:
        fit = next(t for t in table if t.model == LinearModel(name, opt.per_anchor))
        _detail(r, fit, weights, floor, opt.max_lag)
        fits.append(fit)
    best = min(fits, key=lambda f: f.cv_rmse)
    return RadioFit(r, opt, floor, table, fits, best, side, int(block.max()) + 1, rule)
