"""Summary statistics with confidence intervals.

The Student-t quantile is ``scipy.special.stdtrit``, the function ``scipy.stats.t.ppf`` calls (same values bit for
bit): importing ``scipy.stats`` takes about a second, which every figure's command would wait for.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.special import stdtrit

__all__ = ["mean_ci", "mean_ci_columns", "mean_ci_text"]


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


def mean_ci_text(mean: float, half: float, digits: int = 2) -> str:
    """``"MEAN ± HALF"``: the half-width to ``digits`` significant digits, the mean to the same decimal place.

    So that both have the same precision, and no more than the interval supports: ``27 ± 4.303`` is printed
    ``27.0 ± 4.3``, ``2734 ± 143`` is ``2730 ± 140``. A half-width of 0 (one run, or runs all alike) gives the mean
    to 4 significant digits and ``± 0``; a NaN mean (no runs) gives ``n/a``.

    Args:
        mean: The mean.
        half: The half-width of its confidence interval (>= 0).
        digits: Significant digits of the half-width.

    Examples:
        >>> mean_ci_text(21.667, 1.434)
        '21.7 ± 1.4'
        >>> mean_ci_text(0.8, 0.0)
        '0.8 ± 0'
    """
    if not math.isfinite(mean):
        return "n/a"
    if not math.isfinite(half):
        return f"{mean:.4g} ± n/a"
    if half == 0:
        return f"{mean:.4g} ± 0"
    magnitude = math.floor(math.log10(abs(half)))
    decimals = digits - 1 - magnitude
    if abs(round(half, decimals)) >= 10.0 ** (magnitude + 1):  # 9.96 rounds up to 10: one digit fewer
        decimals -= 1
    shown = max(decimals, 0)
    return f"{round(mean, decimals) + 0.0:.{shown}f} ± {round(half, decimals):.{shown}f}"  # + 0.0: no "-0"
