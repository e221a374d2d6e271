"""Link budgets: received signal strength (RSSI, dBm) from distance, walls and shadowing, and packet delivery.

Every radio model of amronet shares one link budget (``../shared/reference/radio.md`` has the sources)::

    RSSI = tx_dbm - pl0_db - 10 n log10(d / 1 m) - wall_db * walls + X        [dBm]

with ``d`` the link length (never below :data:`MIN_DISTANCE_M`), ``n`` the path-loss exponent, ``walls`` the walls
the straight line between the two nodes crosses (multi-wall model only) and ``X`` the link's shadowing in dB.

**Calibration to the paper's range.** A link is *usable* when its RSSI is at or above the threshold. Unless the
scenario gives ``threshold_dbm``, the threshold is derived from ``r_c``: ``threshold = tx_dbm - pl0_db - 10 n
log10(r_c)``, so that without walls and shadowing the median link reaches exactly ``r_c`` (then ``tx_dbm`` and
``pl0_db`` shift every RSSI but decide no link). A scenario that gives ``threshold_dbm`` instead gets the ``r_c``
this implies (:func:`median_range`).

**Margin.** The rules work on the margin ``RSSI - threshold = 10 n log10(r_c / d) - wall_db * walls + X``: a link
is usable when the margin is ``>= 0``.

**Packet delivery ratio** (:func:`delivery_ratio`): the DARPA SubT testbed's QPSK curve, a bit error rate
``erfc(sqrt(SNR))`` and ``PDR = (1 - BER) ** 100`` for 100-byte packets, placed so that the usable threshold is
where 90 % of the packets get through (the 802.11 sensitivity convention: at most 10 % packet error). Then
``PDR(margin) = (1 - erfc(sqrt(10 ** ((margin + SNR_AT_THRESHOLD_DB) / 10)))) ** 100``: 0.5 at -1.68 dB,
0.9 at 0 dB, 0.996 at +2 dB, 0.999 98 at +4 dB, within 1e-12 of 1 from +7.5 dB.

Example:
    >>> b = LinkBudget(r_c=4.0, exponent=2.0)
    >>> round(b.threshold_dbm, 2)
    -32.04
    >>> float(b.margin_db(4.0))
    0.0
    >>> round(float(delivery_ratio(0.0)), 3)
    0.9
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.special import erfc

from amronet.engine.radio_traits import RADIO_BOUNDS, RadioBound, median_range

__all__ = [
    "MIN_DISTANCE_M",
    "PACKET_BYTES",
    "PDR_AT_THRESHOLD",
    "RADIO_BOUNDS",
    "SNR_AT_THRESHOLD_DB",
    "LinkBudget",
    "RadioBound",
    "delivery_ratio",
    "median_range",
]

MIN_DISTANCE_M: float = 0.01
"""Links shorter than this are computed at this length (the log-distance law has no meaning at 0 m)."""

PACKET_BYTES: int = 100
"""Packet size of the delivery-ratio curve (the SubT testbed's example)."""

PDR_AT_THRESHOLD: float = 0.9
"""Delivery ratio of a link exactly at the usable threshold (at most 10 % packet error, as 802.11 sensitivity)."""


def _pdr_of_snr_db(snr_db: np.ndarray | float) -> np.ndarray:
    snr = np.power(10.0, np.asarray(snr_db, dtype=float) / 10.0)
    return np.power(1.0 - erfc(np.sqrt(snr)), PACKET_BYTES)


SNR_AT_THRESHOLD_DB: float = 7.296460777287823
"""Signal-to-noise ratio (dB) at which the curve delivers :data:`PDR_AT_THRESHOLD` (about 7.30 dB).

The root of ``_pdr_of_snr_db(s) - PDR_AT_THRESHOLD`` on [0, 20] dB that ``scipy.optimize.brentq`` finds with
``xtol=1e-12``, written out (importing ``scipy.optimize`` cost every command a third of a second);
``tests/test_radio.py`` solves it again and compares.
"""


def delivery_ratio(margin_db: np.ndarray | float) -> np.ndarray:
    """Packet delivery ratio of links whose RSSI is ``margin_db`` above the usable threshold (see module doc)."""
    return _pdr_of_snr_db(np.asarray(margin_db, dtype=float) + SNR_AT_THRESHOLD_DB)


@dataclass(frozen=True)
class LinkBudget:
    """The numbers of one radio: transmit power, path loss, walls, shadowing, calibrated to ``r_c``.

    Attributes:
        r_c: Median range without walls and shadowing (m); the paper's communication radius.
        tx_dbm: Transmit power plus antenna gains (dBm).
        pl0_db: Path loss at 1 m (dB).
        exponent: Path-loss exponent ``n``.
        wall_db: Loss per wall crossed (dB); 0 for models without walls.
        shadowing_db: Standard deviation of the log-normal shadowing (dB); 0 for none.
        shadowing_corr_m: Decorrelation distance of the shadowing field (m).
        shadowing_clip: Link shadowing is clipped to ``+-shadowing_clip * shadowing_db`` (bounds the longest link).
    """

    r_c: float
    tx_dbm: float = 20.0
    pl0_db: float = 40.0
    exponent: float = 2.5
    wall_db: float = 0.0
    shadowing_db: float = 0.0
    shadowing_corr_m: float = 2.0
    shadowing_clip: float = 3.0

    @property
    def threshold_dbm(self) -> float:
        """The usable-link threshold: the RSSI of a median link of length ``r_c`` without walls."""
        return self.tx_dbm - self.pl0_db - 10.0 * self.exponent * math.log10(self.r_c)

    @property
    def reach(self) -> float:
        """The longest link that can exist: ``r_c`` times the range gain of the largest shadowing allowed."""
        return self.r_c * 10.0 ** (self.shadowing_clip * self.shadowing_db / (10.0 * self.exponent))

    def margin_db(self, d: np.ndarray | float, walls: np.ndarray | float = 0.0,
                  shadowing: np.ndarray | float = 0.0) -> np.ndarray:
        """RSSI minus threshold of links of length ``d`` crossing ``walls`` walls with shadowing ``shadowing``."""
        d = np.maximum(np.asarray(d, dtype=float), MIN_DISTANCE_M)
        return 10.0 * self.exponent * np.log10(self.r_c / d) - self.wall_db * np.asarray(walls) + shadowing

    def rssi_dbm(self, d: np.ndarray | float, walls: np.ndarray | float = 0.0,
                 shadowing: np.ndarray | float = 0.0) -> np.ndarray:
        """Received signal strength (dBm) of links of length ``d`` (see :meth:`margin_db`)."""
        return self.threshold_dbm + self.margin_db(d, walls, shadowing)
