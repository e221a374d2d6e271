"""The answer of :func:`amronet.optimum.find_optimum`: the best placement, the proven bound, and what explains it."""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np

if TYPE_CHECKING:
    from amronet.optimum.instance import Instance

__all__ = ["CAVEAT", "Optimum"]

CAVEAT = ("The optimum is taken over a lattice of candidate sites: it is an upper bound on the optimum with routers "
          "anywhere. The lower bound holds only for this coverage sample (the centres of the reachable map cells) "
          "and this candidate lattice; only the straight-line hop bound holds for any placement.")
"""The caveat every answer carries, in words."""


@dataclass
class Optimum:
    """The best placement found and the lower bound proven for it.

    Attributes:
        map: The map's name.
        bases: Base-station positions (fixed nodes that count 0).
        radio: The radio (model, ``r_c``, link budget, reach).
        spacing: The candidate lattice's spacing (m).
        routers: The best placement's router positions ``(q, 2)``.
        source: What found it (``greedy``, ``local search``, ``coarse lattice``, ``solver``).
        lower: The proven lower bound (routers), the largest of :attr:`bounds`' valid bounds.
        bounds: Each bound: ``solver`` (HiGHS's proven dual bound of the model), ``lp_relaxation``, ``set_cover``
            (coverage without connectivity), ``hop_straight`` and ``hop_lattice``.
        solver: The solver, its status, time, nodes and time limit.
        sample: The coverage sample: cells, cell size, area.
        candidates: The lattice and what the reductions kept.
        seconds: Wall time per phase.
        verified: The placement checked by amronet's own coverage and connectivity code.
        coarse: The coarse lattice's search, when one ran.
        history: The best count after each phase.
    """

    map: str
    bases: list[tuple[float, float]]
    radio: dict[str, Any]
    spacing: float
    routers: np.ndarray
    source: str
    lower: int
    bounds: dict[str, Any]
    solver: dict[str, Any]
    sample: dict[str, Any]
    candidates: dict[str, Any]
    seconds: dict[str, float]
    verified: dict[str, Any]
    coarse: dict[str, Any] | None = None
    history: list[dict[str, Any]] = field(default_factory=list)
    instance: Instance | None = field(default=None, repr=False)
    """The instance it was found on (for the picture); not written."""
    from_store: bool = field(default=False, repr=False)
    """Loaded from a result store, solved before (:mod:`amronet.optimum.stored`); not written."""

    @property
    def count(self) -> int:
        """Routers of the best placement (base stations not counted)."""
        return len(self.routers)

    @property
    def gap(self) -> float | None:
        """``(best - bound) / bound``; 0 when both are 0, ``None`` when only the bound is 0."""
        if self.lower <= 0:
            return 0.0 if self.count == 0 else None
        return (self.count - self.lower) / self.lower

    @property
    def optimal(self) -> bool:
        """Whether the gap is closed: the placement is optimal on this lattice and sample."""
        return self.count <= self.lower

    def to_dict(self) -> dict[str, Any]:
        """The answer as ``optimum.json`` holds it."""
        gap = self.gap
        return {
            "map": self.map, "bases": [list(map(float, b)) for b in self.bases], "radio": self.radio,
            "spacing_m": self.spacing,
            "best": {"routers": self.count, "nodes_total": self.count + len(self.bases), "found_by": self.source,
                     "positions": [[round(float(x), 6), round(float(y), 6)] for x, y in self.routers]},
            "lower_bound": self.lower, "gap": None if gap is None else round(gap, 6), "optimal": self.optimal,
            "bounds": self.bounds, "solver": self.solver, "sample": self.sample, "candidates": self.candidates,
            "coarse": self.coarse, "seconds": {k: round(v, 3) for k, v in self.seconds.items()},
            "verified": self.verified, "history": self.history, "caveat": CAVEAT,
        }

    @classmethod
    def from_dict(cls, doc: dict[str, Any]) -> Optimum:
        """The answer back from what :meth:`to_dict` gave (``optimum.json``, a result store); without its instance."""
        best = doc["best"]
        return cls(map=doc["map"], bases=[(float(x), float(y)) for x, y in doc["bases"]], radio=doc["radio"],
                   spacing=float(doc["spacing_m"]), routers=np.asarray(best["positions"], dtype=float).reshape(-1, 2),
                   source=best["found_by"], lower=int(doc["lower_bound"]), bounds=doc["bounds"], solver=doc["solver"],
                   sample=doc["sample"], candidates=doc["candidates"], seconds=dict(doc["seconds"]),
                   verified=doc["verified"], coarse=doc["coarse"], history=list(doc["history"]))

    def text(self) -> str:
        """A few lines for the terminal."""
        r = self.radio
        radio = "unit disk" if r["model"] == "unit-disk" else f"{r['model']} radio"
        gap = self.gap
        gap_s = "closed" if self.optimal else ("unbounded" if gap is None else f"{100 * gap:.1f} %")
        b = self.bounds
        sc = b["set_cover"]
        lines = [
            f"{self.map}, r_c = {r['r_c']:g} m ({radio}), {len(self.bases)} base station(s), candidates every "
            f"{self.spacing:g} m:",
            f"  best placement: {self.count} routers ({self.count + len(self.bases)} nodes with the base stations), "
            f"found by {self.source}",
            f"  proven lower bound: {self.lower} routers; gap {gap_s}" + (" (optimal)" if self.optimal else ""),
            f"  bounds: solver {_num(b['solver'])}, LP relaxation {_num(b['lp_relaxation'])}, coverage alone "
            f"{sc['lower']}{'' if sc['status'] in ('optimal', 'empty') else ' (not solved to the end)'}, hops "
            f"{b['hop_straight']} (straight line) / {b['hop_lattice']} (lattice)",
            f"  sample: {self.sample['cells']:,} cells of {self.sample['cell_m']:g} m "
            f"({self.sample['reachable_area_m2']:.1f} m² reachable); candidates: {self.candidates['sites']} sites, "
            f"{self.candidates['kept']} after reductions, {self.candidates['rows']} coverage rows",
            f"  solver: {self.solver['name']}, {self.solver['status']} after {self.solver['seconds']:.1f} s "
            f"(limit {self.solver['time_limit_s']:g} s for the whole search, {self.seconds['total']:.1f} s in all)",
            f"  checked by amronet: coverage {100 * self.verified['coverage']:.2f} %, "
            f"{'connected' if self.verified['connected'] else 'NOT connected'}",
            f"  note: {CAVEAT}",
        ]
        return "\n".join(lines) + "\n"


def _num(v: float | None) -> str:
    if v is None:
        return "n/a"
    if isinstance(v, float) and not math.isfinite(v):
        return "inf"
    return f"{v:.2f}" if isinstance(v, float) else str(v)
