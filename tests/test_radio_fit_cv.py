"""amronet radio-fit's cross-validation over blocks of positions: folds hold blocks whole, and blocking matters."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

from amronet.engine.shadowing import ShadowingField
from amronet.radiofit import FitOptions, RadioFitError, fit_radio
from amronet.radiofit.fit import block_size
from amronet.radiofit.linear import block_of_spots, fold_of_blocks
from amronet.radiofit.variogram import fit_gudmundson
from amronet.world.builtin import resolve_map
from test_radio_fit import synthesise


def test_blocks_are_squares_of_the_given_side_and_each_falls_in_one_fold():
    xy = np.random.default_rng(0).uniform(0.0, 10.0, size=(3000, 2))
    block = block_of_spots(xy, 2.0)
    assert block.max() + 1 == 25  # a 10 m square in 2 m blocks
    for b in range(25):  # the spots of a block lie in one 2 m square
        pts = xy[block == b]
        assert np.all(pts.max(axis=0) - pts.min(axis=0) < 2.0)
    fold = fold_of_blocks(np.random.default_rng(1), block, 5)
    for b in range(25):  # no block is split between a training and a test fold
        assert len(np.unique(fold[block == b])) == 1
    sizes = np.bincount(fold, minlength=5)
    assert sizes.min() > 0 and sizes.max() - sizes.min() <= np.bincount(block).max()
    again = fold_of_blocks(np.random.default_rng(1), block, 5)
    other = fold_of_blocks(np.random.default_rng(2), block, 5)
    assert np.array_equal(fold, again) and not np.array_equal(fold, other)  # seeded


def test_block_size_from_the_correlation_distance_and_its_limits():
    g = np.arange(0.25, 20.0, 0.5)  # a 20 m square of positions 0.5 m apart
    xy = np.stack(np.meshgrid(g, g), axis=-1).reshape(-1, 2)
    side, block, rule = block_size(xy, 0.5, 5)
    assert side == 1.5 and block.max() + 1 == 14 * 14 and "correlation distance" in rule
    side, block, _ = block_size(xy, 4.0, 5)  # 12 m blocks: 4 of them, too few for 5 folds; shrunk to 10 or more
    assert side < 12.0 and block.max() + 1 >= 10
    side, block, rule = block_size(xy, float("nan"), 5)
    assert side == 0.0 and np.array_equal(block, np.arange(len(xy))) and "own block" in rule
    side, _, rule = block_size(xy, 0.5, 5, given=2.0)
    assert side == 2.0 and "given" in rule
    with pytest.raises(RadioFitError, match=r"^--block-m: blocks of 10 m hold the positions in 4 blocks"):
        block_size(xy, 0.5, 5, given=10.0)


def test_block_size_ends_when_the_positions_lie_within_a_centimetre():
    # 25 positions within 1.5 cm: no side of 1 cm or more gives 10 blocks, and rounding to 1 cm stops the shrinking
    xy = 4.2 + 0.015 * np.random.default_rng(0).random((25, 2))
    side, block, rule = block_size(xy, 0.74, 5)
    assert side == 0.0 and np.array_equal(block, np.arange(25)) and "own block" in rule


def test_a_variogram_too_short_for_a_covariance_fits_without_a_warning():
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        nugget, sill, _corr = fit_gudmundson(np.array([0.005, 0.01]), np.array([3.0, 3.0]), np.array([10, 10]))
    assert np.isfinite(nugget) and np.isfinite(sill)


def _cv_gap(tmp_path, field_sigma_db: float | None, seed: int) -> tuple[float, float]:
    field = None
    if field_sigma_db is not None:
        field = ShadowingField(resolve_map("office-32x32").extent, field_sigma_db, 5.0, np.random.default_rng(seed))
    _, r = synthesise(tmp_path, n_spots=1500, per_spot=1, noise_db=1.0 if field else 6.0, field=field, seed=seed)
    rf = fit_radio(r, FitOptions(models=("multi-wall",), n_boot=10, seed=0))
    walls = next(t for t in rf.table if t.model.label == "multi-wall")
    return walls.cv_rmse, walls.cv_position_rmse


@pytest.mark.parametrize("seed", [1, 2])
def test_blocked_cv_is_larger_than_per_position_cv_under_correlated_shadowing(tmp_path, seed):
    # A field of 8 dB decorrelating over 5 m: a held-out position's neighbours share its shadowing, and folds of
    # single positions leave them in the training data. Without correlation (6 dB of independent noise) the two
    # agree: blocking changes nothing there.
    blocked, single = _cv_gap(tmp_path, 8.0, seed)
    assert blocked > single + 0.1, (blocked, single)
    blocked, single = _cv_gap(tmp_path, None, seed)
    assert abs(blocked - single) < 0.05, (blocked, single)


def test_buildings_sweep_runs_the_experiments_scenarios_with_the_default_and_the_fitted_radio():
    from pathlib import Path

    from amronet.algorithms.agent_assisted.drops.link_quality import LinkQualityParams
    from amronet.experiments.buildings import BUILDINGS, RADIOS
    from amronet.experiments.common import agent_scenario
    from amronet.scenario import load_scenario
    from amronet.scenario.schema import RadioSpec
    from amronet.sweeps.identity import resolve_scenario
    from amronet.sweeps.spec import load_sweep

    assert LinkQualityParams().drop_margin_db == 8.0
    sweep = load_sweep(Path(__file__).resolve().parents[1] / "docs" / "radio-fit-buildings.yaml")
    assert len(sweep.points) == 12 and len(sweep.runs()) == 120
    fitted = {"path_loss_exponent": 1.0, "wall_db": 5.75, "shadowing_db": 5.97, "shadowing_corr_m": 0.74}
    for p in sweep.points:
        b = BUILDINGS[p.overrides["map"]]
        margin = p.overrides.get("algorithm.params.drop.drop_margin_db")
        drop = {} if margin is None else {"drop_margin_db": margin}  # 8 dB: the experiment's link-quality
        radio = RADIOS["multi-wall"] if p.overrides["radio.path_loss_exponent"] == 2.0 else {
            "model": "multi-wall", **fitted}
        own = agent_scenario(b.map, b.r_c, (b.base,), 3, "frontier", 600.0, radio=radio,
                             drop_rule=p.overrides["algorithm.params.drop_rule"], drop=drop)
        want, got = resolve_scenario(load_scenario(own)), p.scenario
        # the default cells spell out the defaults the experiment leaves to the scenario: the same link budget
        budget_got, budget_want = (RadioSpec(**x["radio"]).link_budget().__dict__ for x in (got, want))
        assert budget_got == budget_want and got["base_stations"] == want["base_stations"], p.overrides
        assert got["algorithm"] == want["algorithm"] and got["agents"] == want["agents"], p.overrides
        assert got["map"] == want["map"] and got["sim"] == want["sim"], p.overrides
