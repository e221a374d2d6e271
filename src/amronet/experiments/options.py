"""The run options shared by the paper's figures, the job runner and the deployment planner.

One frozen :class:`RunOptions` carries how many runs are made and where they execute, so that
:func:`~amronet.experiments.fig5.run_fig5`, :func:`~amronet.experiments.fig7.run_fig7`,
:func:`~amronet.experiments.fig10.run_coverage_over_time`, :func:`~amronet.experiments.runner.run_jobs` and
:func:`amronet.planning.plan` take the same object instead of repeating eight keyword parameters::

    run_fig5(out_dir, radii=(6, 10), options=RunOptions(workers=1, show_progress=False, store="runs.sqlite"))
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

from amronet.errors import AmronetError

if TYPE_CHECKING:
    from amronet.sweeps.executors import Executor

__all__ = ["AGENT_TIME_LIMIT_S", "RUN_OPTIONS", "RunOptions", "check_optimum_options"]

AGENT_TIME_LIMIT_S = 6000.0
"""Default time limit of agent-assisted runs (Figs. 5 and 7, the planner): simulated seconds."""


@dataclass(frozen=True)
class RunOptions:
    """How the runs of a figure (or a plan) are made and where they execute; every field has a default.

    Attributes:
        explorer: The agents' exploration strategy (figures without agents, Figs. 10 and 11, do not use it).
        time_limit: Simulated seconds per run at most; ``None``: the function's own default
            (:data:`AGENT_TIME_LIMIT_S` for Figs. 5 and 7 and the planner, 900 s for Figs. 10 and 11).
        workers: Local worker processes (default: the cores available) when there is no ``executor``.
        show_progress: Draw a progress bar (on stderr).
        seed: Base seed (each function documents how it derives the runs' seeds from it).
        store: Result store (SQLite path) that finished runs are kept in and loaded from; ``None``: none (the
            planner then uses a temporary one).
        executor: Where the runs execute (:class:`~amronet.sweeps.executors.Executor`, e.g. Dask); ``None``: a
            local process pool with ``workers`` processes.
        retry_failed: Run again the runs ``store`` holds as failed (otherwise they stay failed).
        optimum: Compare with the optimum (:mod:`amronet.optimum`), searched for this many seconds per problem and
            kept in ``store``; ``None``: no optimum (only Fig. 5 and the buildings take it).
        optimum_spacing: The optimum's candidate spacing (m); ``None``: ``r_c / 2`` (only with ``optimum``).
        baselines: Also run the location-aware Voronoi baselines (VOR, Minimax, Lloyd) as extra lines; ``None``: the
            paper's algorithms only (only Figs. 10 and 11 take it).
    """

    explorer: str = "frontier"
    time_limit: float | None = None
    workers: int | None = None
    show_progress: bool = True
    seed: int = 0
    store: str | Path | None = None
    executor: Executor | None = None
    retry_failed: bool = False
    optimum: float | None = None
    optimum_spacing: float | None = None
    baselines: bool | None = None

    def time_limit_or(self, default: float) -> float:
        """``time_limit``, or ``default`` when it is ``None``."""
        return default if self.time_limit is None else self.time_limit


RUN_OPTIONS = tuple(f.name for f in dataclasses.fields(RunOptions))
"""The names of :class:`RunOptions`' fields, in order."""


def check_optimum_options(optimum: float | None, spacing: float | None) -> None:
    """Refuse a bad ``optimum`` time limit or ``optimum_spacing``, or a spacing without an optimum (one line).

    Args:
        optimum: Seconds of search per problem (``None``: no optimum).
        spacing: The candidate spacing (m) (``None``: ``r_c / 2``).

    Raises:
        AmronetError: Naming ``--optimum`` or ``--optimum-spacing``.
    """
    if spacing is not None and optimum is None:
        raise AmronetError("--optimum-spacing: only with --optimum (the optimum's candidate spacing); add --optimum "
                           "or leave it out")
    if optimum is not None:
        from amronet.optimum.solve import check_time_limit  # here: the solver's modules load only when asked

        check_time_limit(optimum, "--optimum")
    if spacing is not None and not (isinstance(spacing, int | float) and math.isfinite(spacing) and spacing > 0):
        raise AmronetError(f"--optimum-spacing: must be a finite number of metres > 0, got {spacing!r}")
