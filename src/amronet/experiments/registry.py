"""The paper's figures that ``amronet reproduce`` knows, in one place: the :data:`FIGURES` registry.

A figure is a function ``run_FIG(out_dir=..., options=RunOptions(...), **figure_kwargs) -> report``
(``report["markdown"]`` is printed); the registry names it by ``"module:function"``, so that the module is
imported only when the figure runs (``amronet --help`` stays fast). To add one, add a line at the end::

    _add(Figure("fig12", "amronet.experiments.fig12:run_fig12", quick={"runs": 2}))

Options: a figure takes every field of :class:`~amronet.experiments.options.RunOptions` except those in its
``without`` (option → why not). An option given to :meth:`Figure.run` that the figure does not take is an
error, never silently dropped: ``amronet reproduce fig10 --explorer random`` fails with ``--explorer: fig10 does
not take this option (it runs no agents)``. ``amronet reproduce all`` runs every figure in the order of
:data:`FIGURES` and passes each option given to every figure, so :func:`check_options` refuses, before anything
runs, an option that some figure does not take.
"""

from __future__ import annotations

import importlib
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from amronet.errors import AmronetError
from amronet.experiments.options import RUN_OPTIONS, RunOptions
from amronet.registry import Registry

__all__ = ["FIGURES", "GROUPS", "PAPER", "Figure", "check_options", "group"]


@dataclass(frozen=True)
class Figure:
    """How to reproduce one figure.

    Attributes:
        name: The figure's name (``amronet reproduce NAME``), for messages.
        target: ``"module:function"`` of the figure's function.
        kwargs: Fixed keyword arguments (e.g. which of two figures one function makes).
        quick: Keyword arguments of ``--quick`` (a small subset, for a smoke test); those that are fields of
            :class:`RunOptions` (e.g. ``time_limit``) go into its ``options``.
        without: The :class:`RunOptions` fields the figure does not take → why, in a few words.
    """

    name: str
    target: str
    kwargs: dict[str, Any] = field(default_factory=dict)
    quick: dict[str, Any] = field(default_factory=dict)
    without: dict[str, str] = field(default_factory=dict)

    def function(self) -> Any:
        """The figure's function (imported now)."""
        module, _, name = self.target.partition(":")
        return getattr(importlib.import_module(module), name)

    def run(self, out_dir: Path, quick: bool = False, **options: Any) -> dict[str, Any]:
        """Run the figure into ``out_dir`` with the given ``options`` (fields of :class:`RunOptions`).

        Options that are ``None`` are not given (the figure's own default applies); given options win over
        ``quick``'s.

        Raises:
            AmronetError: The figure does not take a given option (see :func:`check_options`), or its run failed.
            TypeError: An option is not a field of :class:`RunOptions`.
        """
        check_options([self], options)
        given = {k: v for k, v in options.items() if v is not None}
        fixed = {**self.kwargs, **(self.quick if quick else {})}
        run_options = RunOptions(**{**{k: v for k, v in fixed.items() if k in RUN_OPTIONS}, **given})
        figure_kwargs = {k: v for k, v in fixed.items() if k not in RUN_OPTIONS}
        return self.function()(**figure_kwargs, out_dir=Path(out_dir), options=run_options)


def check_options(figures: Iterable[Figure], options: Mapping[str, Any], group_name: str = "all") -> None:
    """Check, before any of ``figures`` runs, that each takes every given option (those that are not ``None``).

    Raises:
        AmronetError: One line naming the first option that a figure does not take, the figure and why; with
            several figures (``reproduce all`` or another group, ``group_name``), also the figures that do take it.
        TypeError: An option is not a field of :class:`RunOptions`.
    """
    figures = list(figures)
    unknown = sorted(set(options) - set(RUN_OPTIONS))
    if unknown:
        raise TypeError(f"unknown run options {unknown}; the options are {list(RUN_OPTIONS)}")
    for name in RUN_OPTIONS:
        if options.get(name) is None:
            continue
        refusing = [f for f in figures if name in f.without]
        if not refusing:
            continue
        first, flag = refusing[0], "--" + name.replace("_", "-")
        message = f"{flag}: {first.name} does not take this option ({first.without[name]})"
        if len(figures) > 1:
            takers = [f.name for f in figures if name not in f.without]
            others = ", ".join(f.name for f in refusing[1:])
            message += (f", nor does {others}" if others else "") + (
                f"; reproduce {group_name} gives every option to every figure, so leave it out"
                + (f" or reproduce {', '.join(takers)} one by one" if takers else ""))
        raise AmronetError(message)


FIGURES: Registry[Figure] = Registry("figure")
"""Figure name → how to reproduce it, in the order ``reproduce all`` runs them."""


def _add(figure: Figure) -> None:
    FIGURES.add(figure.name, figure)


_NO_BASELINES = {"baselines": "only fig10 and fig11 draw the Voronoi baselines"}
_OPTIMUM = {"optimum": "only fig5 and buildings compare with the optimum",
            "optimum_spacing": "only fig5 and buildings compare with the optimum"}
_NO_OPTIMUM = {**_OPTIMUM, **_NO_BASELINES}
_NO_AGENTS = {"explorer": "it runs no agents", **_NO_OPTIMUM}
_SPREADING = {"explorer": "it runs no agents", **_OPTIMUM}

_add(Figure("fig5", "amronet.experiments.fig5:run_fig5", quick={"radii": (6, 10), "agents": (1, 2), "starts": 2},
            without=_NO_BASELINES))
_add(Figure("fig7", "amronet.experiments.fig7:run_fig7", quick={"bases": (1, 2), "agents": (1, 2), "runs": 2},
            without=_NO_OPTIMUM))
_add(Figure("fig10", "amronet.experiments.fig10:run_coverage_over_time", kwargs={"figure": "fig10"},
            quick={"runs": 2, "time_limit": 30.0}, without=_SPREADING))
_add(Figure("fig11", "amronet.experiments.fig10:run_coverage_over_time", kwargs={"figure": "fig11"},
            quick={"runs": 2, "time_limit": 30.0}, without=_SPREADING))
_add(Figure("buildings", "amronet.experiments.buildings:run_buildings",
            quick={"buildings": ("office-32x32", "cave"), "rules": ("last-reference", "link-quality"),
                   "stocks": (None, 6), "runs": 2, "time_limit": 120.0}, without=_NO_BASELINES))
_add(Figure("walks", "amronet.experiments.walks:run_walks",
            quick={"maps": ("autolab",), "runs": 2, "time_limit": 60.0}, without=_NO_AGENTS))
_add(Figure("failures", "amronet.experiments.failures:run_failures",
            quick={"maps": ("autolab",), "fractions": (0.2,), "runs": 2, "fault_at": 60.0, "after": 60.0},
            without=_NO_OPTIMUM))


PAPER: tuple[str, ...] = ("fig5", "fig7", "fig10", "fig11")
"""The paper's four experiments (``amronet reproduce paper``); ``all`` adds the experiments beyond the paper."""
GROUPS: tuple[str, ...] = ("all", "paper")
"""Names ``amronet reproduce`` takes for several figures at once (each into ``OUT/FIGURE``)."""


def group(name: str) -> list[str] | None:
    """The figures of a group name (:data:`GROUPS`) in the order they run, or ``None`` when it names no group."""
    if name == "all":
        return list(FIGURES)
    if name == "paper":
        return [n for n in PAPER if n in FIGURES]
    return None
