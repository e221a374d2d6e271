"""Spatially correlated log-normal shadowing: one Gaussian random field per run, and the shadowing of a link.

**The field.** ``S(p)`` is a zero-mean Gaussian field over the map with standard deviation ``sigma`` (dB) and
Gudmundson's exponential correlation ``corr(S(p), S(q)) = exp(-|p - q| / d_corr)``. It is sampled once per run on
a square grid of cell ``h = d_corr / 8`` (coarser only on maps over 512 such cells a side) by circulant embedding
(Dietrich & Newsam, 1997: the covariance of a periodic grid twice the size is diagonalised by the FFT; the few
negative eigenvalues that the embedding of an exponential covariance can leave are set to zero) from the run's
generator, so the same seed gives the same field. ``S`` at a point is the value of the grid cell holding it.

**The link.** A link between ``a`` and ``b`` gets ``X(a, b) = (S(a) + S(b)) / sqrt(2 (1 + rho))`` with
``rho = exp(-|a - b| / d_corr)``: symmetric (``X(a, b) = X(b, a)`` bit for bit), normal with standard deviation
exactly ``sigma`` for every link length (the field's two values have correlation ``rho``), and correlated in
space: moving either end a little changes it a little, so a place stays good or bad as in a real building. It is
clipped to ``+-clip * sigma`` (3 sigma by default; that lowers its standard deviation by 0.25 %) so that no link
is longer than ``r_c * 10 ** (clip * sigma / (10 n))``, the radius within which the medium searches for links.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numba import njit

__all__ = ["FieldGrid", "ShadowingField", "cell_value", "field_at", "link_shadowing", "values_on_grid"]

_CELLS_PER_CORR = 8
_MAX_SIDE = 512


class FieldGrid(NamedTuple):
    """A shadowing field as the kernels read it: the values of a square grid and where it lies."""

    values: np.ndarray
    """The field's values ``(rows, cols)`` in dB, row 0 at ``y0``."""
    x0: float
    """x of the grid's lower-left corner, metres."""
    y0: float
    """y of the grid's lower-left corner, metres."""
    h: float
    """Cell size, metres."""


class ShadowingField:
    """A sampled shadowing field over a rectangle.

    Args:
        extent: ``(xmin, xmax, ymin, ymax)`` of the area (the map's extent).
        sigma_db: Standard deviation of the field in dB (``> 0``).
        corr_m: Decorrelation distance in metres (``> 0``).
        rng: The generator the field is drawn from.

    Attributes:
        grid: The field's values ``(rows, cols)`` in dB, row 0 at ``ymin``.
        x0, y0: World position of the grid's lower-left corner; h: its cell size.
        sigma_db, corr_m: As given.
    """

    def __init__(self, extent: tuple[float, float, float, float], sigma_db: float, corr_m: float,
                 rng: np.random.Generator) -> None:
        xmin, xmax, ymin, ymax = extent
        span = max(xmax - xmin, ymax - ymin)
        h = max(corr_m / _CELLS_PER_CORR, span / (_MAX_SIDE - 1))
        nx = int(math.ceil((xmax - xmin) / h)) + 1
        ny = int(math.ceil((ymax - ymin) / h)) + 1
        self.sigma_db, self.corr_m = float(sigma_db), float(corr_m)
        self.x0, self.y0, self.h = float(xmin), float(ymin), float(h)
        self.grid = sigma_db * _gaussian_field(ny, nx, h, corr_m, rng)
        self.grid.flags.writeable = False

    def at(self, xy: np.ndarray) -> np.ndarray:
        """``S`` at the points ``xy`` ``(M, 2)`` (the value of the grid cell holding each; clamped at the edges)."""
        xy = np.asarray(xy, dtype=float)
        return _lookup(self.grid, self.x0, self.y0, self.h, xy[:, 0], xy[:, 1])

    @property
    def kernel_grid(self) -> FieldGrid:
        """The field as the kernels read it."""
        return FieldGrid(self.grid, self.x0, self.y0, self.h)


def _gaussian_field(ny: int, nx: int, h: float, corr: float, rng: np.random.Generator) -> np.ndarray:
    """A unit-variance field ``(ny, nx)`` with correlation ``exp(-distance / corr)`` (circulant embedding)."""
    my, mx = 2 * ny, 2 * nx  # the periodic grid: twice the size, so no pair wraps around closer than it is
    dy = np.minimum(np.arange(my), my - np.arange(my)) * h
    dx = np.minimum(np.arange(mx), mx - np.arange(mx)) * h
    cov = np.exp(-np.hypot(dy[:, None], dx[None, :]) / corr)
    eig = np.maximum(np.fft.fft2(cov).real, 0.0)
    z = rng.standard_normal((my, mx)) + 1j * rng.standard_normal((my, mx))
    field = np.fft.fft2(np.sqrt(eig / (my * mx)) * z).real
    return np.ascontiguousarray(field[:ny, :nx])


@njit(cache=True)
def cell_value(grid, x0, y0, h, x, y):  # pragma: no cover - numba
    """``S`` at ``(x, y)`` of the field ``grid`` with origin ``(x0, y0)`` and cell side ``h`` (clamped at the edges).

    :func:`field_at` with the field's arrays and numbers passed one by one (as kernels that take the field apart do).
    """
    i = int(math.floor((y - y0) / h)) if math.isfinite(y) else 0
    j = int(math.floor((x - x0) / h)) if math.isfinite(x) else 0
    i = min(max(i, 0), grid.shape[0] - 1)
    j = min(max(j, 0), grid.shape[1] - 1)
    return grid[i, j]


@njit(cache=True, inline="always")
def field_at(field, x, y):  # pragma: no cover - numba
    """``S`` at ``(x, y)`` of a :class:`FieldGrid` (the value of the grid cell holding it; clamped at the edges)."""
    return cell_value(field.values, field.x0, field.y0, field.h, x, y)


def values_on_grid(field: FieldGrid, cx: np.ndarray, cy: np.ndarray) -> np.ndarray:
    """The field's values at the points of the grid ``cx`` x ``cy`` ``(len(cy), len(cx))``: :func:`cell_value` of each.

    ``cx`` and ``cy``: finite x and y coordinates (``(cols,)`` and ``(rows,)``); a grid row's points share one row of
    the field, a column's one column, so each index is computed once per coordinate (the same operations).
    """
    rows, cols = field.values.shape
    i = np.clip(np.floor((cy - field.y0) / field.h).astype(np.int64), 0, rows - 1)
    j = np.clip(np.floor((cx - field.x0) / field.h).astype(np.int64), 0, cols - 1)
    return field.values[np.ix_(i, j)]


@njit(cache=True)
def _lookup(grid, x0, y0, h, x, y):  # pragma: no cover - numba
    out = np.empty(x.shape[0])
    for k in range(x.shape[0]):
        out[k] = cell_value(grid, x0, y0, h, x[k], y[k])
    return out


@njit(cache=True, inline="always")
def link_shadowing(sa, sb, d, corr, limit):  # pragma: no cover - numba
    """``X(a, b)`` of a link of length ``d`` whose ends see the field values ``sa`` and ``sb``, clipped to ``limit``."""
    x = (sa + sb) / math.sqrt(2.0 * (1.0 + math.exp(-d / corr)))
    return min(max(x, -limit), limit)
