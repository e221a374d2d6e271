"""Tests of amronet.engine.shadowing: reproducible fields, their statistics, and the shadowing of a link.

The statistical tests use one fixed seed, so they are deterministic; their tolerances are still derived from the
sampling error of the estimators (for a Gaussian field it follows from the correlation function alone, by
Isserlis' theorem), so that a correct field passes by a wide margin and a wrong one (a wrong sigma, a wrong
correlation length, a broken embedding) fails.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
import scipy.sparse as sp
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.stats import norm

from amronet.engine.propagation import LinkBudget
from amronet.engine.radio import make_medium
from amronet.engine.shadowing import ShadowingField, link_shadowing, values_on_grid
from amronet.world.builtin import resolve_map

SIGMA = 5.0
CORR = 2.0
CELLS_PER_CORR = 8  # the field's grid cell is CORR / 8 (shadowing.py)
SIDE = 512  # the largest grid the field samples at that cell size
Z = 4.0  # tolerances are Z standard errors: a false alarm for a correct field has probability about 6e-5


def _rho(k: np.ndarray) -> np.ndarray:
    """The field's correlation at lattice offsets ``k`` (in cells): ``exp(-|k| h / d_corr)``."""
    return np.exp(-np.linalg.norm(k, axis=-1) / CELLS_PER_CORR)


def _offsets(reach_cells: int) -> np.ndarray:
    """Every lattice offset within ``reach_cells`` along both axes ``(M, 2)`` (the correlation beyond is < e^-20)."""
    a = np.arange(-reach_cells, reach_cells + 1)
    return np.stack(np.meshgrid(a, a, indexing="ij"), axis=-1).reshape(-1, 2)


@pytest.fixture(scope="module")
def big_field() -> ShadowingField:
    """A field over a square of 511 cells of d_corr / 8 a side (63.9 d_corr): 262,144 values, one FFT of 1024^2."""
    span = (SIDE - 1) * CORR / CELLS_PER_CORR
    field = ShadowingField((0.0, span, 0.0, span), SIGMA, CORR, np.random.default_rng(20240611))
    assert field.h == CORR / CELLS_PER_CORR and field.grid.shape == (SIDE, SIDE)
    return field


def test_same_seed_same_field_bit_for_bit():
    ext = (-3.0, 3.0, -3.0, 3.0)
    a = ShadowingField(ext, SIGMA, CORR, np.random.default_rng(5))
    b = ShadowingField(ext, SIGMA, CORR, np.random.default_rng(5))
    c = ShadowingField(ext, SIGMA, CORR, np.random.default_rng(6))
    assert a.grid.tobytes() == b.grid.tobytes()
    assert a.grid.shape == c.grid.shape and not np.array_equal(a.grid, c.grid)
    assert np.abs(a.grid - c.grid).mean() > 0.5 * SIGMA  # independent fields, not a tiny perturbation
    assert not a.grid.flags.writeable
    # through the medium: the field comes from a child stream of the run's generator
    omap = resolve_map("obstacles-6x6")
    budget = LinkBudget(r_c=1.0, shadowing_db=SIGMA, shadowing_corr_m=CORR)
    m1 = make_medium("log-distance", budget, omap, rng=np.random.default_rng(5))
    m2 = make_medium("log-distance", budget, omap, rng=np.random.default_rng(5))
    m3 = make_medium("log-distance", budget, omap, rng=np.random.default_rng(6))
    assert m1.shadowing.grid.tobytes() == m2.shadowing.grid.tobytes()
    assert not np.array_equal(m1.shadowing.grid, m3.shadowing.grid)


def test_field_grid_and_lookup():
    ext = (-1.0, 2.0, 0.5, 1.5)
    f = ShadowingField(ext, SIGMA, CORR, np.random.default_rng(1))
    assert f.h == CORR / CELLS_PER_CORR and (f.x0, f.y0) == (-1.0, 0.5)
    rows, cols = f.grid.shape
    assert cols * f.h >= 3.0 and rows * f.h >= 1.0  # covers the extent
    pts = np.array([[-1.0, 0.5], [-0.99, 0.76], [0.3, 1.2], [1.99, 1.49], [-50.0, 0.7], [1.0, 99.0]])
    got = f.at(pts)
    assert got[0] == f.grid[0, 0]
    assert got[1] == f.grid[1, 0]  # y 0.76 is in row 1 (0.75 .. 1.0)
    assert got[2] == f.grid[int((1.2 - 0.5) // f.h), int((0.3 + 1.0) // f.h)]
    assert got[4] == f.grid[0, 0]  # clamped at the edges
    assert got[5] == f.grid[-1, int((1.0 + 1.0) // f.h)]
    # a large map gets a coarser grid, never more than 512 cells a side
    big = ShadowingField((0.0, 500.0, 0.0, 20.0), SIGMA, CORR, np.random.default_rng(1))
    assert max(big.grid.shape) <= SIDE and big.h > CORR / CELLS_PER_CORR


def test_field_standard_deviation_is_sigma(big_field):
    g = big_field.grid / SIGMA
    n = g.size
    # The mean square about the known mean 0, V = mean(g^2), has E V = 1 and, for a Gaussian field, variance
    # (2 / N) sum_k rho(k)^2 over all lattice offsets k (Isserlis; edge effects are O(d_corr / side) and
    # neglected). sum_k rho(k)^2 ~ pi d_corr^2 / 2 / h^2 ~ 100 cells: N_eff = N / 100 ~ 2600 effectively
    # independent values, so the standard error of the sample standard deviation sqrt(V) is 1.4 % of sigma
    # (over 40 seeds its spread was 1.3 %): a sigma 6 % off fails.
    var_v = 2.0 / n * float(np.sum(_rho(_offsets(20 * CELLS_PER_CORR)) ** 2))
    se_sd = math.sqrt(var_v) / 2.0
    assert 0.012 < se_sd < 0.016
    sd = math.sqrt(float(np.mean(g * g)))
    assert abs(sd - 1.0) < Z * se_sd, (sd, se_sd)
    assert abs(float(g.mean())) < Z * math.sqrt(float(np.sum(_rho(_offsets(20 * CELLS_PER_CORR)))) / n)


def test_field_correlation_at_d_corr_is_exp_minus_one(big_field):
    g = big_field.grid / SIGMA
    lag = CELLS_PER_CORR  # the lattice lag of exactly d_corr
    v = float(np.mean(g * g))
    cx = float(np.mean(g[:, :-lag] * g[:, lag:]))
    cy = float(np.mean(g[:-lag] * g[lag:]))
    r = 0.5 * (cx + cy) / v
    # Standard error of the ratio r_x = C_x / V (lag h along x), by the delta method around (E C, E V) =
    # (rho_h, 1), with the covariances of products of a Gaussian field (Isserlis), per offset k:
    #   N Var C    = sum rho(k)^2 + rho(k + h) rho(k - h)
    #   N Cov(C,V) = sum 2 rho(k) rho(k - h)
    #   N Var V    = sum 2 rho(k)^2
    #   Var r_x    = Var C - 2 rho_h Cov(C, V) + rho_h^2 Var V
    # r averages r_x and r_y, whose variances are equal, so Var r <= Var r_x (Cauchy-Schwarz). It comes to
    # 0.015 (over 40 seeds the spread of r was 0.012); a d_corr 20 % off moves r by 4.4 se, 25 % by 5.4 se.
    k = _offsets(20 * CELLS_PER_CORR)
    h = np.array([lag, 0])
    rho_h = math.exp(-1.0)
    n = g.shape[0] * (g.shape[1] - lag)
    var_c = float(np.sum(_rho(k) ** 2 + _rho(k + h) * _rho(k - h))) / n
    cov_cv = float(np.sum(2.0 * _rho(k) * _rho(k - h))) / n
    var_v = float(np.sum(2.0 * _rho(k) ** 2)) / n
    se = math.sqrt(var_c - 2 * rho_h * cov_cv + rho_h**2 * var_v)
    assert 0.008 < se < 0.02
    assert abs(r - rho_h) < Z * se, (r, se)
    # and the correlation decays: about exp(-1/2) at half the distance, exp(-2) at twice (looser: 1 se each)
    for lag2, want in ((CELLS_PER_CORR // 2, math.exp(-0.5)), (2 * CELLS_PER_CORR, math.exp(-2.0))):
        c = 0.5 * (float(np.mean(g[:, :-lag2] * g[:, lag2:])) + float(np.mean(g[:-lag2] * g[lag2:]))) / v
        assert abs(c - want) < Z * 1.5 * se, (lag2, c, want)


def _clipped_sd(clip: float) -> float:
    """Standard deviation of a standard normal clipped to [-clip, clip] (values beyond set to the bound)."""
    q, p = norm.sf(clip), norm.pdf(clip)
    return math.sqrt(1.0 - 2.0 * (clip * p + q) + 2.0 * clip * clip * q)


def test_link_shadowing_symmetric_with_sd_sigma():
    rng = np.random.default_rng(3)
    n = 200_000
    d = rng.uniform(0.0, 4 * CORR, n)
    rho = np.exp(-d / CORR)
    # field values at the two ends: correlated normals with correlation rho(d)
    za, zb = rng.standard_normal((2, n))
    sa = SIGMA * za
    sb = SIGMA * (rho * za + np.sqrt(1 - rho**2) * zb)
    lim = 3.0 * SIGMA
    x = np.array([link_shadowing(a, b, dd, CORR, lim) for a, b, dd in zip(sa, sb, d, strict=True)])
    y = np.array([link_shadowing(b, a, dd, CORR, lim) for a, b, dd in zip(sa, sb, d, strict=True)])
    assert np.array_equal(x, y)  # bit for bit
    assert np.abs(x).max() <= lim and np.abs(x).max() == lim
    # Independent samples: the standard error of a sample sd is sd / sqrt(2 n) = 0.16 % here.
    se = 1.0 / math.sqrt(2 * n)
    want = _clipped_sd(3.0)  # 0.99750: clipping at 3 sigma lowers the sd by 0.25 % (truncating would by 1.3 %)
    assert abs(want - 0.99750) < 1e-5
    assert abs(x.std() / SIGMA - want) < Z * se
    assert abs(x.mean()) / SIGMA < Z / math.sqrt(n)
    # unclipped, exactly sigma for every link length: check short and long links separately
    xu = np.array([link_shadowing(a, b, dd, CORR, 1e9) for a, b, dd in zip(sa, sb, d, strict=True)])
    for part in (d < CORR / 2, d > 2 * CORR):
        assert abs(xu[part].std() / SIGMA - 1.0) < Z / math.sqrt(2 * part.sum())
    # a zero-length link sees its one field value
    assert link_shadowing(1.5, 1.5, 0.0, CORR, lim) == 1.5


def test_link_shadowing_over_the_field(big_field):
    # Links of length d_corr along the lattice (both ends on cell values): X = (S(a) + S(a + delta)) /
    # sqrt(2 (1 + e^-1)), itself a stationary Gaussian field with correlation
    # rho_X(k) = (2 rho(k) + rho(k + delta) + rho(k - delta)) / (2 (1 + rho(delta))); the standard error of its
    # sample sd is sqrt((2 / N) sum_k rho_X(k)^2) / 2, as for the field.
    f = big_field
    g = f.grid
    lag = CELLS_PER_CORR
    rows, cols = g.shape
    ii, jj = np.meshgrid(np.arange(rows), np.arange(cols - lag), indexing="ij")
    a = np.column_stack([f.x0 + (jj.ravel() + 0.5) * f.h, f.y0 + (ii.ravel() + 0.5) * f.h])
    b = a + np.array([CORR, 0.0])
    sa, sb = f.at(a), f.at(b)
    assert np.array_equal(sa, g[:, :-lag].ravel()) and np.array_equal(sb, g[:, lag:].ravel())
    lim = 3.0 * SIGMA
    x = np.array([link_shadowing(p, q, CORR, CORR, lim) for p, q in zip(sa, sb, strict=True)])
    k = _offsets(20 * CELLS_PER_CORR)
    delta = np.array([lag, 0])
    rho_x = (2 * _rho(k) + _rho(k + delta) + _rho(k - delta)) / (2 * (1 + math.exp(-1.0)))
    se = math.sqrt(2.0 / x.size * float(np.sum(rho_x**2))) / 2.0
    assert se < 0.02
    sd = math.sqrt(float(np.mean(x * x))) / SIGMA
    assert abs(sd - _clipped_sd(3.0)) < Z * se, (sd, se)


def test_medium_applies_link_shadowing_symmetrically():
    omap = resolve_map("obstacles-6x6")
    budget = LinkBudget(r_c=1.0, exponent=2.5, shadowing_db=SIGMA, shadowing_corr_m=CORR)
    medium = make_medium("log-distance", budget, omap, rng=np.random.default_rng(11))
    xy = np.random.default_rng(12).uniform(-2.9, 2.9, (150, 2))
    table = medium.update(xy)
    cand = table.geometric
    rows = np.repeat(np.arange(len(xy)), cand.degree)
    cols = cand.indices
    s = medium.shadowing.at(xy)
    want = np.array([10 * budget.exponent * math.log10(budget.r_c / d) + link_shadowing(s[i], s[j], d, CORR, 15.0)
                     for i, j, d in zip(rows, cols, cand.dist, strict=True)])
    np.testing.assert_allclose(cand.margin, want, rtol=0, atol=1e-9)
    # the candidates reach as far as the largest shadowing allows, and links are the candidates with margin >= 0
    assert cand.r == pytest.approx(budget.r_c * 10 ** (15.0 / 25.0))
    assert (cand.dist > budget.r_c).any() and (table.dist > budget.r_c).any()
    assert len(table.indices) == int((cand.margin >= 0).sum())
    m = sp.csr_matrix((table.rssi, table.indices, table.indptr), shape=(len(xy), len(xy)))
    assert (m != m.T).nnz == 0


@settings(max_examples=40, deadline=None)
@given(st.floats(-3.0, 3.0), st.floats(-3.0, 3.0), st.floats(0.01, 0.7), st.integers(1, 40), st.integers(1, 40),
       st.integers(0, 2**32 - 1))
def test_values_on_a_grid_are_the_lookups_of_its_points(ox, oy, res, rows, cols, seed):
    """:func:`values_on_grid` equals the field's lookup at every point of the grid, bit for bit (edges clamped)."""
    field = ShadowingField((0.0, 6.0, 0.0, 4.0), 4.0, 1.0, np.random.default_rng(seed))
    cy = oy + (np.arange(rows) + 0.5) * res  # the coverage grid's cell centres, partly off the field's extent
    cx = ox + (np.arange(cols) + 0.5) * res
    xx, yy = np.meshgrid(cx, cy)
    expected = field.at(np.column_stack([xx.ravel(), yy.ravel()])).reshape(rows, cols)
    np.testing.assert_array_equal(values_on_grid(field.kernel_grid, cx, cy), expected)
