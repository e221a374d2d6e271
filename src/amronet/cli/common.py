"""Argument helpers shared by the ``amronet`` subcommands: base-station positions and where runs execute."""

from __future__ import annotations

import argparse
import math
from typing import Any

from amronet.errors import AmronetError

__all__ = ["add_executor_arguments", "make_executor_from_args", "parse_base", "parse_point"]


def parse_point(text: str, option: str = "--base", example: str = "1.0,2.0") -> tuple[float, float]:
    """Parse a point option ``X,Y`` in metres (``--base``, ``--node``).

    Raises:
        AmronetError: Not two finite numbers (names ``option``).
    """
    try:
        x, y = (float(v) for v in text.split(","))
    except ValueError:
        raise AmronetError(f"{option}: {text!r} is not X,Y in metres, e.g. {example}") from None
    if not (math.isfinite(x) and math.isfinite(y)):
        raise AmronetError(f"{option}: {text!r} must be finite")
    return x, y


def parse_base(text: str) -> tuple[float, float]:
    """Parse ``--base X,Y`` (metres); see :func:`parse_point`."""
    return parse_point(text)


def add_executor_arguments(parser: argparse.ArgumentParser, force: bool = True) -> None:
    """Add ``--workers``, ``--scheduler`` and ``--cluster``: where the runs of a command execute.

    Args:
        parser: The subcommand's parser.
        force: Also add ``--force`` (more ``--workers`` than cores); ``False`` for a command whose own ``--force``
            acknowledges that too.
    """
    parser.add_argument("--workers", type=int, help="local worker processes, or LocalCluster workers, at most one "
                                                    "per run (default: all cores; more than the cores only with "
                                                    "--force, never more than the memory holds; not with "
                                                    "--scheduler)")
    parser.add_argument("--scheduler", metavar="ADDRESS", help="run on a running Dask scheduler, e.g. tcp://host:8786")
    parser.add_argument("--cluster", metavar="KIND", help="start a Dask cluster here: local (a LocalCluster)")
    if force:
        parser.add_argument("--force", action="store_true", help="start more --workers than there are cores")


def make_executor_from_args(args: argparse.Namespace) -> Any:
    """The executor (a context manager) that :func:`add_executor_arguments`'s options ask for.

    Raises:
        AmronetError: ``--workers`` below 1, above the cores without ``--force`` or above the memory
            (:func:`~amronet.sweeps.worker_bounds.check_workers`), or with ``--scheduler`` (or a bad scheduler /
            cluster, from the executor).
    """
    from amronet.sweeps import make_executor

    return make_executor(workers=args.workers, scheduler=args.scheduler, cluster=args.cluster,
                         force=getattr(args, "force", False))
