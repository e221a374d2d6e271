"""Summary statistics with confidence intervals."""

from __future__ import annotations

import numpy as np
from scipy import stats

__all__ = ["mean_ci", "mean_ci_columns"]


def mean_ci(values: np.ndarray, confidence: float = 0.95) -> tuple[float, float]:
    """Mean and half-width of its two-sided Student-t confidence interval.

    Args:
        values: Samples (NaNs are dropped).
        confidence: Confidence level.

    Returns:
        ``(mean, half_width)``; the half-width is 0 for a single sample and both are NaN for none.
    """
    x = np.asarray(values, dtype=float)
    x = x[~np.isnan(x)]
    if len(x) == 0:
        return float("nan"), float("nan")
    if len(x) == 1:
        return float(x[0]), 0.0
    half = stats.t.ppf(0.5 + confidence / 2, len(x) - 1) * x.std(ddof=1) / np.sqrt(len(x))
    return float(x.mean()), float(half)


def mean_ci_columns(samples: np.ndarray, confidence: float = 0.95) -> tuple[np.ndarray, np.ndarray]:
    """Column-wise :func:`mean_ci` of ``samples`` ``(runs, points)``: the mean curve and its half-width curve."""
    x = np.asarray(samples, dtype=float)
    n = x.shape[0]
    mean = x.mean(axis=0)
    if n < 2:
        return mean, np.zeros_like(mean)
    half = stats.t.ppf(0.5 + confidence / 2, n - 1) * x.std(axis=0, ddof=1) / np.sqrt(n)
    return mean, half
