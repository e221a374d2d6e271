"""The paper's figures that ``amronet reproduce`` knows, in one place.

A figure is a function ``run_FIG(out_dir=..., **options) -> report`` (``report["markdown"]`` is printed). To add
one, add one line to :data:`FIGURES`::

    "fig12": Figure("amronet.experiments.fig12:run_fig12", quick={"runs": 2}),

``amronet reproduce`` passes the options the function accepts among ``workers``, ``show_progress``,
``explorer``, ``time_limit``, ``store``, ``executor`` and ``retry_failed`` (others, and options not given, are
left out, so a figure need not take them all), and ``quick`` with ``--quick``. ``amronet reproduce all`` runs
every figure in the order of :data:`FIGURES`.
"""

from __future__ import annotations

import importlib
import inspect
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

__all__ = ["FIGURES", "Figure"]


@dataclass(frozen=True)
class Figure:
    """How to reproduce one figure.

    Attributes:
        target: ``"module:function"`` of the figure's function.
        kwargs: Fixed keyword arguments (e.g. which of two figures one function makes).
        quick: Keyword arguments of ``--quick`` (a small subset, for a smoke test).
    """

    target: str
    kwargs: dict[str, Any] = field(default_factory=dict)
    quick: dict[str, Any] = field(default_factory=dict)

    def function(self) -> Any:
        """The figure's function (imported now)."""
        module, _, name = self.target.partition(":")
        return getattr(importlib.import_module(module), name)

    def run(self, out_dir: Path, quick: bool = False, **options: Any) -> dict[str, Any]:
        """Run the figure into ``out_dir`` with the ``options`` its function accepts.

        Options that are ``None`` are left out (the figure's own default applies); given options win over
        ``quick``'s.
        """
        fn = self.function()
        params = inspect.signature(fn).parameters
        takes_all = any(p.kind is inspect.Parameter.VAR_KEYWORD for p in params.values())
        accepted = {k: v for k, v in options.items() if v is not None and (takes_all or k in params)}
        return fn(**{**self.kwargs, **(self.quick if quick else {}), **accepted, "out_dir": Path(out_dir)})


FIGURES: dict[str, Figure] = {
    "fig5": Figure("amronet.experiments.fig5:run_fig5", quick={"radii": (6, 10), "agents": (1, 2), "starts": 2}),
    "fig7": Figure("amronet.experiments.fig7:run_fig7", quick={"bases": (1, 2), "agents": (1, 2), "runs": 2}),
    "fig10": Figure("amronet.experiments.fig10:run_coverage_over_time", kwargs={"figure": "fig10"},
                    quick={"runs": 2, "time_limit": 30.0}),
    "fig11": Figure("amronet.experiments.fig10:run_coverage_over_time", kwargs={"figure": "fig11"},
                    quick={"runs": 2, "time_limit": 30.0}),
}
"""Figure name → how to reproduce it, in the order ``reproduce all`` runs them."""
