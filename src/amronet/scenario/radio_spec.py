"""The ``radio`` section of a scenario: the radio medium and its link budget, each number within its bounds."""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any

from pydantic import ValidationInfo, field_validator, model_validator

from amronet.engine.radio_traits import DEFAULT_WALL_DB, RADIO_BOUNDS, median_range, traits_of
from amronet.scenario.fields import MAX_RANGE_M, FiniteFloat, NonNegativeFloat, PositiveFloat, Strict
from amronet.yaml_fields import YamlBool

if TYPE_CHECKING:
    from amronet.engine.propagation import LinkBudget

__all__ = ["RadioSpec"]


class RadioSpec(Strict):
    """The radio medium and its link budget (:mod:`amronet.engine.propagation`, :mod:`amronet.engine.radio`).

    Fields left out (``None``) take the model's defaults: path-loss exponent 2.5 for ``log-distance`` and the
    unit disk's RSSI, 2.0 for ``multi-wall``; shadowing 5 dB for ``log-distance``, none otherwise; 6.9 dB per
    wall (COST 231 heavy wall) for ``multi-wall``.
    """

    model: str = "unit-disk"
    """The radio model: ``unit-disk`` (the paper's: a link within ``r_c``), ``log-distance`` or ``multi-wall``."""
    r_c: PositiveFloat = 1.0
    """Median range without walls and shadowing (m): the usable threshold is derived from it."""
    tx_dbm: FiniteFloat = 20.0
    """Transmit power (dBm); only ``tx_dbm - pl0_db`` matters for a link."""
    pl0_db: FiniteFloat = 40.0
    """Path loss at 1 m (dB)."""
    path_loss_exponent: PositiveFloat | None = None
    """Path-loss exponent ``n``; ``null``: the model's default."""
    wall_db: NonNegativeFloat | None = None
    """Loss per wall crossed (dB); ``multi-wall`` only."""
    shadowing_db: NonNegativeFloat | None = None
    """Standard deviation of the spatially correlated log-normal shadowing (dB); not for the unit disk."""
    shadowing_corr_m: PositiveFloat = 2.0
    """Distance over which the shadowing decorrelates (m; Gudmundson's exponential model)."""
    threshold_dbm: FiniteFloat | None = None
    """The usable-link threshold (dBm); given, it sets ``r_c`` (the median range it implies), so give one of the two."""
    packet_loss: YamlBool = False
    """Drop each link in each step with probability one minus its packet delivery ratio."""

    @field_validator(*RADIO_BOUNDS, mode="before")
    @classmethod
    def _in_bounds(cls, value: Any, info: ValidationInfo) -> Any:
        """Refuse a number outside the field's physical range (:data:`~amronet.engine.radio_traits.RADIO_BOUNDS`)."""
        problem = RADIO_BOUNDS[str(info.field_name)].problem(value)
        if problem is not None:
            raise ValueError(f"@radio.{info.field_name}@{problem}")
        return value

    @model_validator(mode="after")
    def _check_budget(self) -> RadioSpec:
        if self.r_c > MAX_RANGE_M:
            raise ValueError(f"@radio.r_c@{self.r_c:g} m is beyond the longest range amronet models, "
                             f"{MAX_RANGE_M:g} m; give a range in metres, e.g. 1.5")
        cls = traits_of(self.model)  # the traits alone: no engine to refuse a scenario
        if cls is None:
            return self  # the scenario names the unknown model
        given = self.model_fields_set
        if not cls.uses_walls and self.wall_db is not None:
            raise ValueError(f"@radio.wall_db@the {self.model} model has no walls; use radio.model=multi-wall or "
                             "leave wall_db out")
        if not cls.uses_shadowing and (self.shadowing_db or 0.0) > 0:
            raise ValueError(f"@radio.shadowing_db@the {self.model} model has no shadowing; use radio.model="
                             "log-distance or multi-wall, or leave shadowing_db out")
        if self.threshold_dbm is not None:
            n = self.path_loss_exponent or cls.default_exponent
            implied = median_range(self.tx_dbm, self.pl0_db, n, self.threshold_dbm)
            if implied < 0.05:
                at = self.tx_dbm - self.pl0_db - 10.0 * n * math.log10(0.05)
                raise ValueError(f"@radio.threshold_dbm@{self.threshold_dbm:g} dBm is never reached: the transmitter "
                                 f"delivers {at:.1f} dBm at 5 cm; lower the threshold or raise radio.tx_dbm")
            if implied > MAX_RANGE_M:
                raise ValueError(f"@radio.threshold_dbm@{self.threshold_dbm:g} dBm puts the median range at "
                                 f"{implied:.3g} m; raise the threshold (or give radio.r_c instead)")
            if "r_c" in given and not math.isclose(implied, self.r_c, rel_tol=1e-9):
                raise ValueError(f"@radio.threshold_dbm@{self.threshold_dbm:g} dBm implies r_c = {implied:.6g} m but "
                                 f"radio.r_c is {self.r_c:g}; give only one of the two")
            object.__setattr__(self, "r_c", implied)
        return self

    def link_budget(self) -> LinkBudget:
        """The link budget of this radio, the model's defaults filled in."""
        from amronet.engine.propagation import LinkBudget  # (SciPy) here: a scenario is checked without it
        from amronet.engine.radio import MEDIA

        cls = MEDIA.lookup(self.model, "radio.model")
        shadowing = self.shadowing_db if self.shadowing_db is not None else cls.default_shadowing_db
        wall = self.wall_db if self.wall_db is not None else DEFAULT_WALL_DB
        return LinkBudget(r_c=self.r_c, tx_dbm=self.tx_dbm, pl0_db=self.pl0_db,
                          exponent=self.path_loss_exponent or cls.default_exponent,
                          wall_db=wall if cls.uses_walls else 0.0,
                          shadowing_db=shadowing if cls.uses_shadowing else 0.0,
                          shadowing_corr_m=self.shadowing_corr_m)
