"""The censored (Tobit) fit: a link the anchor did not hear is a reading below the receiver's floor.

An anchor reports nothing when the signal is below its sensitivity, so the heard readings of far and through-wall
links are biased towards strong values and least squares on them alone flattens the law (a lower exponent, a
smaller wall loss). With the (point, anchor) pairs that have no reading, the censored regression of Tobin (1958)
fits the same linear law by maximum likelihood: a heard reading contributes the normal density of its residual, a
censored link the probability ``Phi((floor - mu) / sigma)`` that its RSSI fell below ``floor_dbm``. This assumes
every missing reading was missed for weakness (not packet loss), and one floor for all anchors. When readings go
missing for other reasons too (lost packets, short time bins), the *truncated* fit (:func:`fit_censored`) is the
safer one: it uses only the heard readings, each weighted by the chance it had to be heard.
"""

from __future__ import annotations

import numpy as np
from scipy.optimize import minimize
from scipy.special import log_ndtr

__all__ = ["fit_censored", "fit_tobit"]

_LOG_SQRT_2PI = 0.5 * np.log(2.0 * np.pi)


def _nll(params: np.ndarray, x: np.ndarray, y: np.ndarray, w: np.ndarray, xc: np.ndarray, floor: float,
         wc: np.ndarray) -> tuple[float, np.ndarray]:
    """Weighted negative log-likelihood (up to a constant) and its gradient in ``(theta, log sigma)``."""
    theta, s = params[:-1], params[-1]
    sigma = np.exp(s)
    r = (y - x @ theta) / sigma
    z = (floor - xc @ theta) / sigma
    logcdf = log_ndtr(z)
    lam = np.exp(-0.5 * z * z - _LOG_SQRT_2PI - logcdf)  # phi(z) / Phi(z), stable far into the tail
    nll = float(np.sum(w * (s + 0.5 * r * r)) - np.sum(wc * logcdf))
    g_theta = -(x.T @ (w * r)) / sigma + (xc.T @ (wc * lam)) / sigma
    g_s = float(np.sum(w * (1.0 - r * r)) + np.sum(wc * lam * z))
    return nll, np.append(g_theta, g_s)


def _nll_truncated(params: np.ndarray, x: np.ndarray, y: np.ndarray, floor: float) -> tuple[float, np.ndarray]:
    """Negative log-likelihood of the heard readings as a normal law truncated below ``floor``, and its gradient."""
    theta, s = params[:-1], params[-1]
    sigma = np.exp(s)
    r = (y - x @ theta) / sigma
    u = (x @ theta - floor) / sigma  # a reading is heard with probability Phi(u)
    logcdf = log_ndtr(u)
    lam = np.exp(-0.5 * u * u - _LOG_SQRT_2PI - logcdf)
    nll = float(np.sum(s + 0.5 * r * r + logcdf))
    g_theta = -(x.T @ r) / sigma + (x.T @ lam) / sigma
    g_s = float(np.sum(1.0 - r * r - lam * u))
    return nll, np.append(g_theta, g_s)


def fit_censored(x: np.ndarray, y: np.ndarray, floor_dbm: float, start: np.ndarray) -> tuple[np.ndarray, float]:
    """Maximum-likelihood coefficients and sigma of the heard readings as a law truncated below ``floor_dbm``.

    Needs no knowledge of the missing readings: each heard one is weighted by the chance it had to be heard
    (truncated regression). It corrects the bias of the floor whatever else made readings go missing.
    """
    r = y - x @ start
    s0 = np.log(max(float(np.sqrt(np.mean(r * r))), 1e-3))
    res = minimize(_nll_truncated, np.append(start, s0), args=(x, y, floor_dbm), jac=True, method="L-BFGS-B")
    return res.x[:-1], float(np.exp(res.x[-1]))


def fit_tobit(x: np.ndarray, y: np.ndarray, xc: np.ndarray, floor_dbm: float, start: np.ndarray,
              w: np.ndarray | None = None, wc: np.ndarray | None = None) -> tuple[np.ndarray, float]:
    """Maximum-likelihood coefficients and sigma of the censored linear model.

    Args:
        x: Design matrix of the heard readings ``(R, p)``.
        y: Their RSSI ``(R,)``.
        xc: Design matrix of the censored links ``(C, p)``.
        floor_dbm: The receiver's floor: a censored link's RSSI is below it.
        start: Starting coefficients (the least-squares fit).
        w: Weights of the heard readings (bootstrap counts); ones if ``None``.
        wc: Weights of the censored links; ones if ``None``.

    Returns:
        The coefficients ``(p,)`` and sigma (dB).
    """
    w = np.ones(len(y)) if w is None else w
    wc = np.ones(len(xc)) if wc is None else wc
    r = y - x @ start
    s0 = np.log(max(float(np.sqrt(np.sum(w * r * r) / max(np.sum(w), 1.0))), 1e-3))
    res = minimize(_nll, np.append(start, s0), args=(x, y, w, xc, floor_dbm, wc), jac=True, method="L-BFGS-B")
    return res.x[:-1], float(np.exp(res.x[-1]))
