"""amronet radio-fit: the fitter recovers amronet's own models, and the fitted block reproduces the fit."""

from __future__ import annotations

import math

import numpy as np
import pytest

from amronet.engine.propagation import LinkBudget
from amronet.engine.radio import make_medium
from amronet.engine.shadowing import ShadowingField, link_shadowing
from amronet.radiofit import FitOptions, fit_radio, load_readings, predict_with_block, radio_block
from amronet.radiofit.data import link_geometry
from amronet.radiofit.linear import LinearModel, design
from amronet.world.builtin import resolve_map

ANCHORS = np.array([[4.0, 4.0, 2.5], [28.0, 5.0, 2.0], [6.0, 27.0, 2.2], [26.0, 26.0, 2.8], [16.0, 16.0, 2.4]])


def synthesise(tmp_path, *, n_spots=1500, per_spot=2, a_dbm=-40.0, n=2.2, wall_db=6.0, noise_db=4.0,
               field: ShadowingField | None = None, floor_dbm=None, seed=1, tag_height=1.0):
    """Readings drawn from amronet's link budget on office-32x32, written as the command's CSV files."""
    omap = resolve_map("office-32x32")
    rng = np.random.default_rng(seed)
    xy = rng.uniform(0.5, 31.5, size=(4 * n_spots, 2))
    xy = xy[omap.is_free(xy)][:n_spots]
    budget = LinkBudget(r_c=10.0, tx_dbm=a_dbm + 40.0, pl0_db=40.0, exponent=n, wall_db=wall_db)
    rows = []
    for k, anc in enumerate(ANCHORS):
        d, walls = link_geometry(omap, np.repeat(anc[None], len(xy), 0), xy, tag_height)
        shadow = np.zeros(len(xy))
        if field is not None:
            sa, sb = field.at(anc[None, :2])[0], field.at(xy)
            shadow = np.array([link_shadowing(sa, s, float(dd), field.corr_m, 3.0 * field.sigma_db)
                               for s, dd in zip(sb, d, strict=True)])
        mean = budget.rssi_dbm(d, walls, shadow)
        for j in range(per_spot):
            rows.append((j * len(xy) + np.arange(len(xy)), xy, np.full(len(xy), k + 1),
                         mean + noise_db * rng.standard_normal(len(xy))))
    lines = ["point,x,y,anchor,rssi_dbm"]
    for pts, p, anc, rssi in rows:
        keep = np.ones(len(rssi), bool) if floor_dbm is None else rssi >= floor_dbm
        cols = zip(pts[keep], p[keep], anc[keep], rssi[keep], strict=True)
        lines += [f"{q},{float(x)!r},{float(y)!r},{a},{float(v)!r}" for q, (x, y), a, v in cols]
    (tmp_path / "rssi.csv").write_text("\n".join(lines) + "\n")
    (tmp_path / "anchors.csv").write_text("id,x,y,z\n" + "".join(f"{i + 1},{x},{y},{z}\n"
                                                                  for i, (x, y, z) in enumerate(ANCHORS)))
    return omap, load_readings(omap, tmp_path / "anchors.csv", tmp_path / "rssi.csv", tag_height)


def test_recovers_multi_wall_parameters_within_their_standard_errors(tmp_path):
    _omap, r = synthesise(tmp_path)
    rf = fit_radio(r, FitOptions(models=("multi-wall",), n_boot=100, seed=3))
    fit = rf.fits[0]
    x = design(fit.model, r.anchor, r.d, r.walls, r.n_anchors)
    # readings at one spot are independent here, so the OLS standard errors hold: sigma^2 (X'X)^-1
    se_ols = 4.0 * np.sqrt(np.diag(np.linalg.inv(x.T @ x)))
    se_boot = fit.boot.std(axis=0, ddof=1)
    assert np.all((se_boot > 0.6 * se_ols) & (se_boot < 1.6 * se_ols))
    truth = np.array([-40.0, 2.2, 6.0])
    assert np.all(np.abs(fit.coef - truth) < 4.0 * se_ols)
    # the spread: sigma within 4 standard errors of a sample standard deviation of R readings
    assert abs(fit.sigma - 4.0) < 4.0 * 4.0 / math.sqrt(2 * len(r.rssi))
    # multi-wall beats log-distance out of sample, and CV RMSE is about the noise
    table = {t.model.label: t for t in rf.table}
    assert table["multi-wall"].cv_rmse < table["log-distance"].cv_rmse - 1.0
    assert abs(table["multi-wall"].cv_rmse - 4.0) < 0.15


def test_recovers_shadowing_spread_and_correlation_distance(tmp_path):
    field = ShadowingField(resolve_map("office-32x32").extent, 6.0, 2.0, np.random.default_rng(7))
    _, r = synthesise(tmp_path, n_spots=2500, per_spot=1, noise_db=1.0, wall_db=0.0, field=field)
    rf = fit_radio(r, FitOptions(models=("log-distance",), n_boot=50, seed=0, max_lag=8.0))
    fit = rf.fits[0]
    nugget, _sill, corr = fit.gudmundson
    assert abs(corr - 2.0) < 0.6, fit.gudmundson  # one field realisation: a few tens of correlation lengths
    assert nugget < 3.0  # only the 1 dB noise (1 dB^2) varies between readings at one spot
    assert 4.8 < fit.sigma < 7.2  # the field's 6 dB (plus 1 dB noise), from one realisation
    lo, hi = np.percentile(fit.boot_gudmundson[:, 2], [2.5, 97.5])
    assert lo < corr < hi


def test_truncated_and_tobit_fits_undo_the_floor_bias(tmp_path):
    _, r = synthesise(tmp_path, a_dbm=-40.0, n=3.0, wall_db=0.0, noise_db=6.0, floor_dbm=-78.0, n_spots=1200)
    rf = fit_radio(r, FitOptions(models=("log-distance",), n_boot=20, seed=0, floor_dbm=-78.0))
    fit = rf.fits[0]
    assert len(r.cens_spot) > 0.1 * (len(r.rssi) + len(r.cens_spot))
    assert fit.coef[1] < 2.8  # least squares on the heard readings flattens the law
    tr = fit.censoring["truncated"]["coef"]["path_loss_exponent"]
    tb = fit.censoring["tobit"]["coef"]["path_loss_exponent"]
    assert abs(tr - 3.0) < 0.15 and abs(tb - 3.0) < 0.1
    assert abs(fit.censoring["tobit"]["sigma_db"] - 6.0) < 0.3


@pytest.mark.parametrize("per_anchor", [False, True])
def test_emitted_block_reproduces_the_fit_through_amronets_link_budget(tmp_path, per_anchor):
    omap, r = synthesise(tmp_path, n_spots=400, n=0.9)  # exponent below amronet's bound: held at 1
    rf = fit_radio(r, FitOptions(models=("multi-wall",), per_anchor=per_anchor, n_boot=10, seed=0))
    fit = rf.fits[0]
    assert fit.held == {"path_loss_exponent": 1.0}
    block = radio_block(fit, r, rf.floor_dbm)
    mine = fit.predict(r, fit.scenario_coef)
    if per_anchor:  # one radio for all anchors: the constants' mean over the readings
        a = fit.scenario_coef[:r.n_anchors]
        mine = mine - a[r.anchor] + np.mean(a[r.anchor])
    np.testing.assert_allclose(predict_with_block(block, r), mine, atol=1e-4)
    # and the medium's own margin kernel, with its own wall counting, for sample links
    from amronet.engine.hearing import path_loss_margin
    from amronet.scenario.schema import RadioSpec

    budget = RadioSpec(**block).link_budget()
    medium = make_medium("multi-wall", LinkBudget(**{**budget.__dict__, "shadowing_db": 0.0}), omap)
    for i in range(0, len(r.rssi), len(r.rssi) // 7):
        ax, ay, _ = r.anchor_xyz[r.anchor[i]]
        tx, ty = r.spot_xy[r.spot[i]]
        m = path_loss_margin(ax, ay, tx, ty, r.d[i], 0.0, 0.0, -1e9, medium.hearing)
        assert m + budget.threshold_dbm == pytest.approx(mine[i], abs=1e-4)


def test_per_anchor_fit_recovers_anchor_constants(tmp_path):
    _, r = synthesise(tmp_path, n_spots=600)
    fit = fit_radio(r, FitOptions(models=("multi-wall",), per_anchor=True, n_boot=20, seed=0)).fits[0]
    assert fit.names[:5] == [f"a_dbm[{i}]" for i in range(1, 6)]
    se = fit.boot.std(axis=0, ddof=1)
    assert np.all(np.abs(fit.coef[:5] + 40.0) < 4.0 * se[:5])
    assert LinearModel("multi-wall", True).label == "multi-wall per-anchor"
