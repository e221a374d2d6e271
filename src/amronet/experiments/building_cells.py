"""The cells of ``amronet reproduce buildings``: its floor plans, drop rules, radios and stocks (data only).

Kept apart from :mod:`~amronet.experiments.buildings` (which runs them) so that
:mod:`~amronet.experiments.buildings_optimum` reads the same cells without importing the experiment.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

__all__ = ["BUILDINGS", "RADIOS", "RULES", "STOCKS", "TIME_LIMIT_S", "Building"]

TIME_LIMIT_S = 600.0
"""Default simulated seconds per run."""


@dataclass(frozen=True)
class Building:
    """A floor plan of the experiment: its base station (a free point) and the ``r_c`` that suits its size."""

    map: str
    base: tuple[float, float]
    r_c: float


BUILDINGS: dict[str, Building] = {b.map: b for b in (
    Building("office-32x32", (1.0, 1.0), 6.0),       # the paper's corner base station (Figs. 5 and 7)
    Building("autolab", (2.5, 10.0), 4.0),           # the self-spreading demo's base station; reaches 209 of 333 m²
    Building("hospital_section", (3.0, 6.0), 4.0),   # west end; reaches 458 m² of the 635 m² free
    Building("depot", (3.0, 1.5), 5.0),              # south-west corner; reaches 437 of 449 m²
    Building("cave", (-6.4, -6.4), 4.0),             # south-west; reaches 196 of 251 m²
)}
"""The buildings, with base stations at free points that reach most of each map's free space."""

RULES: dict[str, tuple[str, dict[str, Any]]] = {
    "last-reference": ("last-reference", {}),
    "link-quality": ("link-quality", {}),
    "link-quality-3dB": ("link-quality", {"drop_margin_db": 3.0}),
    "radius": ("radius", {}),
    "distance-junction": ("distance-junction", {}),
}
"""Label → (drop rule, its parameters): every rule at its defaults, and link-quality tuned for open space (3 dB)."""

RADIOS: dict[str, dict[str, Any]] = {
    "unit-disk": {},
    "multi-wall": {"model": "multi-wall", "shadowing_db": 4.0},
}
"""Label → radio fields beyond ``r_c``."""

STOCKS: tuple[int | None, ...] = (None, 12, 6)
"""Routers each agent carries (``None``: unlimited)."""
