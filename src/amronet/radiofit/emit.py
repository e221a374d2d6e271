"""The fitted model as a scenario's ``radio:`` block, and its prediction through amronet's own link budget.

amronet's link budget (:class:`~amronet.engine.propagation.LinkBudget`) predicts ``RSSI = tx_dbm - pl0_db - 10 n
log10(d) - wall_db * walls``. The fit determines only ``A = tx_dbm - pl0_db`` (the RSSI at 1 m), so the block
keeps amronet's ``pl0_db`` (40 dB, the free-space loss at 1 m at 2.4 GHz) and puts ``tx_dbm = A + pl0_db``; any
other split predicts the same RSSI. With one constant per anchor, the block takes their mean over the readings (a
scenario has one radio). ``threshold_dbm`` is the receivers' floor in the data: it sets ``r_c``, not the RSSI; it is
left out when the median range it implies is beyond what a scenario takes (then give ``r_c``).

amronet's media measure links in the plane; the fit's lengths are 3-D (anchors above the tag). For nodes at one
height the block is the fitted law; :func:`predict_with_block` feeds it the 3-D lengths to check it.
"""

from __future__ import annotations

import numpy as np

from amronet.engine.propagation import median_range
from amronet.radiofit.data import Readings
from amronet.radiofit.fit import ModelFit
from amronet.scenario.schema import MAX_RANGE_M, RadioSpec

__all__ = ["PL0_DB", "predict_with_block", "radio_block", "set_lines"]

PL0_DB = 40.0
"""``pl0_db`` of the block: amronet's default (only ``tx_dbm - pl0_db`` is fitted)."""


def radio_block(fit: ModelFit, r: Readings, floor_dbm: float) -> dict:
    """The ``radio`` fields that reproduce the fit's mean prediction (its parameters held at amronet's bounds)."""
    coef = dict(zip(fit.names, fit.scenario_coef.tolist(), strict=True))
    a = [v for k, v in coef.items() if k.startswith("a_dbm")]
    a_dbm = float(np.mean(np.asarray(a)[r.anchor])) if fit.model.per_anchor else a[0]
    block = {"model": fit.model.model, "tx_dbm": round(a_dbm + PL0_DB, 6), "pl0_db": PL0_DB,
             "path_loss_exponent": round(coef["path_loss_exponent"], 6)}
    if "wall_db" in coef:
        block["wall_db"] = round(coef["wall_db"], 6)
    block["shadowing_db"] = round(float(fit.sigma), 6)
    corr = fit.gudmundson[2]
    if np.isfinite(corr):
        block["shadowing_corr_m"] = round(float(np.clip(corr, 0.1, 1000.0)), 6)
    implied = median_range(block["tx_dbm"], PL0_DB, block["path_loss_exponent"], floor_dbm)
    if 0.05 <= implied <= MAX_RANGE_M:  # else a scenario refuses it: r_c is left to the user
        block["threshold_dbm"] = round(float(floor_dbm), 6)
    return block


def set_lines(block: dict) -> list[str]:
    """The block as ``--set radio.KEY=VALUE`` options."""
    return [f"--set radio.{k}={v:g}" if not isinstance(v, str) else f"--set radio.{k}={v}" for k, v in block.items()]


def predict_with_block(block: dict, r: Readings) -> np.ndarray:
    """RSSI of every reading of ``r`` as amronet computes it for a scenario with this ``radio`` block.

    The block goes through the scenario's own validation and defaults
    (:meth:`~amronet.scenario.schema.RadioSpec.link_budget`), the walls through amronet's wall counting
    (:func:`~amronet.radiofit.data.link_geometry`, the rule of the media); the lengths are the 3-D ones.
    """
    budget = RadioSpec(**block).link_budget()
    return budget.rssi_dbm(r.d, r.walls)
