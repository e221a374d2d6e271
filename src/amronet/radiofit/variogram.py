"""The spatial correlation of the residuals: empirical variogram and Gudmundson's exponential model.

For each anchor, pairs of its readings whose tag positions are ``h`` apart (2-D, up to ``max_lag``) give the
semivariance ``gamma(h) = mean((r_i - r_j)^2) / 2`` of the residuals ``r``, binned by ``h``. Gudmundson's model
(1991) of shadowing correlated as ``exp(-h / d_corr)`` gives ``gamma(h) = nugget + sill (1 - exp(-h / d_corr))``;
the nugget is what varies between readings at one spot (fast fading left after averaging, noise), the sill what
varies with position. It is fitted by weighted least squares (weights: pairs per bin).

Under amronet's link shadowing (:mod:`amronet.engine.shadowing`) a link's value mixes the field at both ends, so
for a fixed anchor about half the variance moves with the tag (a sill near ``shadowing_db**2 / 2``); the
decorrelation distance is the field's ``shadowing_corr_m`` either way.

The bootstrap resamples spots: a pair of spots drawn ``w_i`` and ``w_j`` times counts ``w_i w_j`` times, so the
pairs are summed once per (bin, spot, spot) into sparse matrices and all resamples are one product with them (the
residuals are those of the full fit: the variogram's spread, not the mean fit's, is resampled).
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass

import numpy as np
from scipy import sparse
from scipy.optimize import OptimizeWarning, curve_fit
from scipy.spatial import cKDTree

__all__ = ["CORR_BOUNDS_M", "Variogram", "empirical_variogram", "fit_gudmundson", "gudmundson"]

CORR_BOUNDS_M = (0.01, 1000.0)
"""The correlation distances (m) Gudmundson's fit may return; a fit at the lower bound found no correlation."""


@dataclass(frozen=True)
class Variogram:
    """An empirical variogram, and the pair sums its bootstrap reuses.

    Attributes:
        edges: Bin edges of the lag (m).
        lag: Mean lag of each bin's pairs (m).
        gamma: Semivariance of each bin (dB^2).
        pairs: Pairs in each bin.
        sums: The pair sums ``(3, nb * S, S)`` as sparse matrices: squared differences, lags and pair counts of
            the readings of spots ``i`` (row ``bin * S + i``) and ``j`` (column), summed over anchors.
    """

    edges: np.ndarray
    lag: np.ndarray
    gamma: np.ndarray
    pairs: np.ndarray
    sums: tuple

    def resampled(self, spot_w: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Lag, semivariance and pair count per bin for spot weights ``spot_w (B, S)``: each ``(B, nb)``."""
        nb, n_spots = len(self.edges) - 1, spot_w.shape[1]
        wt = np.ascontiguousarray(spot_w.T)
        sq, h, n = ((m @ wt).reshape(nb, n_spots, -1).__mul__(wt[None]).sum(axis=1).T for m in self.sums)
        with np.errstate(invalid="ignore", divide="ignore"):
            return h / n, sq / (2.0 * n), n


def empirical_variogram(spot_xy: np.ndarray, spot: np.ndarray, anchor: np.ndarray, resid: np.ndarray,
                        max_lag: float = 3.0, bin_m: float = 0.1) -> Variogram:
    """The residuals' variogram over pairs of readings of the same anchor, up to ``max_lag`` metres apart.

    Readings are summed per (spot, anchor) first (count, sum, sum of squares): the pair sums between two such
    groups follow exactly from those, so pairs are enumerated between spots, not readings.
    """
    edges = np.arange(0.0, max_lag + 0.5 * bin_m, bin_m)
    nb, n_spots = len(edges) - 1, len(spot_xy)
    group = anchor * n_spots + spot
    keys, inv = np.unique(group, return_inverse=True)
    cnt = np.bincount(inv).astype(float)
    s1 = np.bincount(inv, weights=resid)
    s2 = np.bincount(inv, weights=resid * resid)
    g_anchor, g_spot = np.divmod(keys, n_spots)
    rows, cols, sq, hs, npair = [], [], [], [], []
    within = cnt > 1  # pairs of readings at one spot: lag 0
    rows.append(g_spot[within])
    cols.append(g_spot[within])
    sq.append(cnt[within] * s2[within] - s1[within] ** 2)
    hs.append(np.zeros(int(within.sum())))
    npair.append(cnt[within] * (cnt[within] - 1.0) / 2.0)
    for a in np.unique(g_anchor):
        idx = np.flatnonzero(g_anchor == a)
        pts = spot_xy[g_spot[idx]]
        pairs = cKDTree(pts).query_pairs(edges[-1], output_type="ndarray")
        i, j = idx[pairs[:, 0]], idx[pairs[:, 1]]
        h = np.hypot(*(spot_xy[g_spot[i]] - spot_xy[g_spot[j]]).T)
        k = np.minimum((h / bin_m).astype(np.int64), nb - 1)
        rows.append(k * n_spots + g_spot[i])
        cols.append(g_spot[j])
        sq.append(cnt[j] * s2[i] + cnt[i] * s2[j] - 2.0 * s1[i] * s1[j])
        hs.append(h * cnt[i] * cnt[j])
        npair.append(cnt[i] * cnt[j])
    r, c = np.concatenate(rows), np.concatenate(cols)
    shape = (nb * n_spots, n_spots)
    sums = tuple(sparse.csr_matrix((np.concatenate(v), (r, c)), shape=shape) for v in (sq, hs, npair))
    v = Variogram(edges, np.zeros(nb), np.zeros(nb), np.zeros(nb), sums)
    lag, gamma, n = (a[0] for a in v.resampled(np.ones((1, n_spots))))
    return Variogram(edges, lag, gamma, n, sums)


def gudmundson(h: np.ndarray, nugget: float, sill: float, corr_m: float) -> np.ndarray:
    """Gudmundson's exponential variogram ``nugget + sill (1 - exp(-h / corr_m))`` (for ``h > 0``)."""
    return nugget + sill * (1.0 - np.exp(-np.asarray(h) / corr_m))


def fit_gudmundson(lag: np.ndarray, gamma: np.ndarray, pairs: np.ndarray) -> tuple[float, float, float]:
    """``(nugget, sill, corr_m)`` of Gudmundson's model fitted to the bins with pairs, weighted by pair count."""
    ok = (pairs > 0) & np.isfinite(gamma)
    lag, gamma, pairs = lag[ok], gamma[ok], pairs[ok]
    top = float(np.max(gamma))
    p0 = (float(gamma[0]) * 0.5, max(top - float(gamma[0]) * 0.5, 1e-3), 1.0)
    try:
        bounds = ([0.0, 0.0, CORR_BOUNDS_M[0]], [np.inf, np.inf, CORR_BOUNDS_M[1]])
        with warnings.catch_warnings():  # the covariance is not used: a variogram too short for it is no news
            warnings.simplefilter("ignore", OptimizeWarning)
            (nug, sill, corr), _ = curve_fit(gudmundson, lag, gamma, p0=p0, sigma=1.0 / np.sqrt(pairs),
                                             bounds=bounds, max_nfev=2000)
    except RuntimeError:  # no convergence: a flat variogram, nothing correlated to see
        return float(np.average(gamma, weights=pairs)), 0.0, float("nan")
    return float(nug), float(sill), float(corr)
