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
from typing import NamedTuple

import numpy as np
from scipy.special import erfc

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


class RadioBound(NamedTuple):
    """The physically meaningful range of one field of a link budget, and where it comes from."""

    lo: float
    hi: float
    unit: str
    source: str
    """Why these bounds, in a few words (the values measured or published)."""
    example: float
    """A typical value, for the error message."""

    def problem(self, value: object) -> str | None:
        """What is wrong with ``value`` as this field (one line ending in the fix), or ``None`` if it is in range.

        Only numbers are judged (not ``bool``): anything else is left to the type's own check.
        """
        if isinstance(value, bool) or not isinstance(value, int | float):
            return None
        if self.lo <= value <= self.hi:  # NaN fails both comparisons
            return None
        unit = f" {self.unit}" if self.unit else ""
        try:
            shown = f"{value:g}"
        except OverflowError:  # an integer beyond any float
            shown = f"a {value.bit_length()}-bit integer"
        return (f"{shown}{unit} is outside [{self.lo:g}, {self.hi:g}]{unit}, {self.source}; "
                f"give e.g. {self.example:g}")


RADIO_BOUNDS: dict[str, RadioBound] = {
    "tx_dbm": RadioBound(-60.0, 60.0, "dBm", "transmit power plus antenna gains from 1 nW to 1 kW (Wi-Fi: 20)",
                         20.0),
    "pl0_db": RadioBound(0.0, 100.0, "dB", "the free-space loss at 1 m (12 dB at 100 MHz, 40 at 2.4 GHz, "
                                          "68 at 60 GHz)", 40.0),
    "path_loss_exponent": RadioBound(1.0, 8.0, "", "around the exponents measured indoors (COST 231: 1.4 along "
                                                   "corridors to 4 in dense offices; ITU-R P.1238: 2.2 to 3; up to "
                                                   "6 when obstructed)", 2.5),
    "wall_db": RadioBound(0.0, 60.0, "dB", "the loss of one wall (COST 231: light 3.4, heavy 6.9; concrete "
                                           "without windows 15; 60 is a metal wall)", 6.9),
    "shadowing_db": RadioBound(0.0, 30.0, "dB", "around the standard deviations measured (3-12 dB indoors; "
                                                "Stage and ns-3: 5)", 5.0),
    "shadowing_corr_m": RadioBound(0.1, 1000.0, "m", "around the decorrelation distances measured (1-5 m indoors, "
                                                     "tens to hundreds of metres outdoors: Gudmundson)", 2.0),
    "threshold_dbm": RadioBound(-174.0, 60.0, "dBm", "from the thermal noise in 1 Hz (-174 dBm) to the strongest "
                                                     "transmitter (receiver sensitivities: -148 to -60 dBm)", -75.0),
}
"""Bounds of the fields of a scenario's ``radio`` section (``radio.<name>``) that are numbers of the link budget;
``r_c`` has its own, (0, 100 km] (:data:`amronet.scenario.MAX_RANGE_M`). Within them no arithmetic of the budget
overflows (the longest reach, ``r_c * 10 ** (3 * 30 / 10)``, is 10^9 ``r_c``)."""


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


def median_range(tx_dbm: float, pl0_db: float, exponent: float, threshold_dbm: float) -> float:
    """Distance (m) at which the median RSSI without walls and shadowing equals ``threshold_dbm``."""
    return 10.0 ** ((tx_dbm - pl0_db - threshold_dbm) / (10.0 * exponent))


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
