"""What a scenario checks of its radio before the engine is imported: the models' traits, the bounds of the budget.

Light on purpose (no NumPy, SciPy or numba): validating a scenario -- and refusing a bad one -- needs only these.
:data:`RADIO_TRAITS` repeats, model by model, the traits the classes of :mod:`amronet.engine.radio` declare (a
test checks that the two agree); :data:`RADIO_BOUNDS` and :func:`median_range` belong to the link budget
(:mod:`amronet.engine.propagation`, which re-exports them).
"""

from __future__ import annotations

import sys
from dataclasses import dataclass, fields
from typing import NamedTuple

__all__ = ["DEFAULT_WALL_DB", "RADIO_BOUNDS", "RADIO_TRAITS", "RadioBound", "RadioTraits", "median_range",
           "model_names", "traits_of"]

DEFAULT_WALL_DB: float = 6.9
"""Loss per wall crossed when none is given: COST 231's heavy internal wall (dB)."""


@dataclass(frozen=True)
class RadioTraits:
    """What a radio model is, as far as a scenario's ``radio`` section goes (the class attributes of the same names).

    Attributes:
        uses_walls: Walls cost ``wall_db`` each (``radio.wall_db`` is refused otherwise).
        uses_shadowing: Links have log-normal shadowing (``radio.shadowing_db`` above 0 is refused otherwise).
        default_exponent: Path-loss exponent when the scenario gives none.
        default_shadowing_db: Shadowing when the scenario gives none.
    """

    uses_walls: bool = False
    uses_shadowing: bool = False
    default_exponent: float = 2.5
    default_shadowing_db: float = 0.0


RADIO_TRAITS: dict[str, RadioTraits] = {
    "unit-disk": RadioTraits(),
    "log-distance": RadioTraits(uses_shadowing=True, default_exponent=2.5, default_shadowing_db=5.0),
    "multi-wall": RadioTraits(uses_walls=True, uses_shadowing=True, default_exponent=2.0),
}
"""Every radio model of :data:`amronet.engine.radio.MEDIA` by name, with its traits (``radio.model``)."""


def _registered() -> dict[str, type]:
    """The models of :data:`amronet.engine.radio.MEDIA` if that module is imported, else none.

    Not imported, it holds no model that :data:`RADIO_TRAITS` lacks (importing it would cost what this module saves).
    """
    radio = sys.modules.get("amronet.engine.radio")
    return dict(radio.MEDIA.items()) if radio is not None and hasattr(radio, "MEDIA") else {}


def traits_of(model: str) -> RadioTraits | None:
    """The traits of the radio model named ``model``, ``None`` for an unknown name.

    A model registered at run time (by code that imported :mod:`amronet.engine.radio` and added its class to
    ``MEDIA``) has the traits its class declares.
    """
    traits = RADIO_TRAITS.get(model)
    if traits is None and model in (registered := _registered()):
        traits = RadioTraits(*(getattr(registered[model], f.name) for f in fields(RadioTraits)))
    return traits


def model_names() -> list[str]:
    """Every radio model's name, sorted: :data:`RADIO_TRAITS` and any registered at run time."""
    return sorted({*RADIO_TRAITS, *_registered()})


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


def median_range(tx_dbm: float, pl0_db: float, exponent: float, threshold_dbm: float) -> float:
    """Distance (m) at which the median RSSI without walls and shadowing equals ``threshold_dbm``."""
    return 10.0 ** ((tx_dbm - pl0_db - threshold_dbm) / (10.0 * exponent))
