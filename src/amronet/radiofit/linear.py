"""The path-loss laws as linear models, fitted by (weighted) least squares in closed form, vectorised.

amronet's link budget (:mod:`amronet.engine.propagation`) predicts ``RSSI = A - 10 n log10(d) - W walls`` with
``A = tx_dbm - pl0_db``: the RSSI at 1 m. The coefficients are linear, so the fit is ordinary least squares on
the columns ``1`` (or one indicator per anchor with ``per_anchor``), ``-10 log10(d)`` and ``-walls`` (multi-wall
only). Only ``A`` as a whole is identifiable: ``tx_dbm`` and ``pl0_db`` enter as their difference.

A bootstrap resample of spots is a weighted least-squares fit (a reading's weight is how often its spot was
drawn), so all resamples are solved at once: their normal equations are one matrix product.

Cross-validation deals spots to folds one by one (:func:`fold_of_spots`) or square blocks of spots at once
(:func:`block_of_spots`, :func:`fold_of_blocks`), so that a held-out spot's neighbours are held out with it.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["MODELS", "LinearModel", "block_of_spots", "design", "fit_weighted", "fold_of_blocks", "fold_of_spots",
           "spot_weights"]

MODELS = ("log-distance", "multi-wall")
"""The radio models a fit can choose (amronet's names, ``radio.model``)."""


@dataclass(frozen=True)
class LinearModel:
    """Which law and which constant term: the columns of the design matrix.

    Attributes:
        model: ``log-distance`` or ``multi-wall``.
        per_anchor: One constant ``A`` per anchor instead of one for all.
    """

    model: str
    per_anchor: bool = False

    def names(self, anchor_ids: np.ndarray) -> list[str]:
        """The coefficients' names, in the columns' order."""
        a = [f"a_dbm[{i}]" for i in anchor_ids] if self.per_anchor else ["a_dbm"]
        return [*a, "path_loss_exponent", *(["wall_db"] if self.model == "multi-wall" else [])]

    @property
    def label(self) -> str:
        """A short name for tables: the model, and ``per-anchor`` when it has one constant per anchor."""
        return f"{self.model}{' per-anchor' if self.per_anchor else ''}"


def design(m: LinearModel, anchor: np.ndarray, d: np.ndarray, walls: np.ndarray, n_anchors: int) -> np.ndarray:
    """The design matrix ``(R, p)`` of links with anchors ``anchor``, lengths ``d`` and wall counts ``walls``."""
    cols = []
    if m.per_anchor:
        cols.append((anchor[:, None] == np.arange(n_anchors)[None, :]).astype(float))
    else:
        cols.append(np.ones((len(d), 1)))
    cols.append(-10.0 * np.log10(d)[:, None])
    if m.model == "multi-wall":
        cols.append(-np.asarray(walls, dtype=float)[:, None])
    return np.hstack(cols)


def fit_weighted(x: np.ndarray, y: np.ndarray, w: np.ndarray) -> np.ndarray:
    """Least-squares coefficients for each row of reading weights ``w (B, R)``: ``(B, p)``.

    Coefficients that no weighted reading determines (an anchor none of whose spots was drawn) come out as NaN.
    """
    p = x.shape[1]
    outer = (x[:, :, None] * x[:, None, :]).reshape(len(x), p * p)
    g = (w @ outer).reshape(len(w), p, p)
    rhs = w @ (x * y[:, None])
    out = np.full((len(w), p), np.nan)
    for b in range(len(w)):  # a few hundred small systems; lstsq handles a column without data
        used = np.diag(g[b]) > 0
        sol, *_ = np.linalg.lstsq(g[b][np.ix_(used, used)], rhs[b, used], rcond=None)
        out[b, used] = sol
    return out


def spot_weights(rng: np.random.Generator, n_spots: int, n_boot: int) -> np.ndarray:
    """How often each spot is drawn in each of ``n_boot`` bootstrap resamples of ``n_spots`` spots: ``(B, S)``."""
    draws = rng.integers(0, n_spots, size=(n_boot, n_spots))
    flat = draws + (np.arange(n_boot) * n_spots)[:, None]
    return np.bincount(flat.ravel(), minlength=n_boot * n_spots).reshape(n_boot, n_spots).astype(float)


def fold_of_spots(rng: np.random.Generator, n_spots: int, k: int) -> np.ndarray:
    """A fold ``0..k-1`` for each spot: a seeded shuffle dealt round-robin (folds differ in size by at most one)."""
    fold = np.empty(n_spots, np.int64)
    fold[rng.permutation(n_spots)] = np.arange(n_spots) % k
    return fold


def block_of_spots(spot_xy: np.ndarray, block_m: float) -> np.ndarray:
    """The square block ``0..B-1`` of side ``block_m`` holding each spot (a grid from the spots' lower-left corner).

    Blocks are numbered in the order of their grid cells (row by row); only blocks that hold a spot get a number.
    """
    cell = np.floor((spot_xy - spot_xy.min(axis=0)) / block_m).astype(np.int64)
    _, block = np.unique(cell, axis=0, return_inverse=True)
    return block.reshape(-1)


def fold_of_blocks(rng: np.random.Generator, block: np.ndarray, k: int) -> np.ndarray:
    """A fold ``0..k-1`` for each spot such that all spots of a block share one fold, the folds about equal in spots.

    The blocks are taken in a seeded random order, each into the fold that holds the fewest spots so far (ties:
    the lowest fold), so folds differ in spots by at most the largest block. Needs at least ``k`` blocks.
    """
    size = np.bincount(block)
    order = rng.permutation(len(size))
    fold_of_block = np.empty(len(size), np.int64)
    held = np.zeros(k, np.int64)
    for b in order:
        f = int(np.argmin(held))
        fold_of_block[b] = f
        held[f] += size[b]
    return fold_of_block[block]
