"""Summary statistics with confidence intervals.

The Student-t quantile is ``scipy.special.stdtrit``, the function ``scipy.stats.t.ppf`` calls (same values bit for
bit): importing ``scipy.stats`` takes about a second, which every figure's command would wait for.
"""

from __future__ import annotations

import numpy as np
from scipy.special import stdtrit

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
    half = stdtrit(len(x) - 1, 0.5 + confidence / 2) * x.std(ddof=1) / np.sqrt(len(x))
    return float(x.mean()), float(half)


def mean_ci_columns(samples: np.ndarray, confidence: float = 0.95) -> tuple[np.ndarray, np.ndarray]:
    """Column-wise :func:`mean_ci` of ``samples`` ``(runs, points)``: the mean curve and its half-width curve."""
    x = np.asarray(samples, dtype=float)
    n = x.shape[0]
    mean = x.mean(axis=0)
    if n < 2:
        return mean, np.zeros_like(mean)
    half = stdtrit(n - 1, 0.5 + confidence / 2) * x.std(axis=0, ddof=1) / np.sqrt(n)
    return mean, half
