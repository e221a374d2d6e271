"""The ``amronet compile`` subcommand: compile the simulator's kernels into numba's cache, saying how far it is.

``amronet compile [--jobs N] [--fresh] [--large-runs] [-q]`` runs the warm-up (:func:`amronet.sim.warmup.warm_up`):
short runs that reach every kernel, grouped by what they warm up (an algorithm, an explorer, a radio model, ...),
on ``--jobs`` worker processes that compile each kernel once between them (:mod:`amronet.kernel_cache_lock`). The
threaded kernels that only runs of 30 000 robots or more use compile with ``--large-runs`` (or in such a run's
first step). As each group starts, stderr gets one line naming it, its number, how many are left and the seconds
elapsed (``[  12 s] compiling kernel group 3 of 32 (29 to go): signal map``); on a terminal, one line updated in
place instead (:class:`CompileProgress`). ``--quiet`` prints only the closing line, on stdout. A group that fails
ends it with one line (``amronet: error: kernel group ... failed (...)``) and exit status 2.
"""

from __future__ import annotations

import argparse
import logging
import os
import sys
import time
from collections.abc import Callable
from types import TracebackType
from typing import Any, TextIO

from amronet.errors import AmronetError

__all__ = ["CompileProgress", "add_parser", "cmd_compile"]


class CompileProgress:
    """Reports which kernel group compiles, how many are left and the seconds elapsed.

    Use it as a context manager; pass :meth:`started` and :meth:`finished` to the warm-up.

    Args:
        total: How many kernel groups compile.
        stream: Where the report goes (stderr).
        live: One line updated in place (a terminal; drawn by rich) instead of one line per group as it starts (a
            log file, a pipe, ``make``'s output).
        clock: Seconds, for the elapsed time.
    """

    def __init__(self, total: int, stream: TextIO, live: bool, clock: Callable[[], float] = time.perf_counter
                 ) -> None:
        self.total = total
        self.begun = 0
        self.done = 0
        self.running: list[str] = []
        self._stream = stream
        self._clock = clock
        self._t0 = clock()
        self._bar: Any = None
        if live:
            from rich.console import Console
            from rich.progress import (
                BarColumn,
                MofNCompleteColumn,
                Progress,
                SpinnerColumn,
                TextColumn,
                TimeElapsedColumn,
            )

            self._bar = Progress(SpinnerColumn(), TextColumn("compiling kernels"), BarColumn(), MofNCompleteColumn(),
                                 TimeElapsedColumn(), TextColumn("{task.description}"),
                                 console=Console(file=stream), transient=True)
            self._task = self._bar.add_task("", total=total)

    def __enter__(self) -> CompileProgress:
        if self._bar is not None:
            self._bar.start()
        return self

    def __exit__(self, kind: type[BaseException] | None, exc: BaseException | None, tb: TracebackType | None) -> None:
        if self._bar is not None:
            self._bar.stop()

    def started(self, label: str) -> None:
        """A kernel group starts compiling."""
        self.begun += 1
        self.running.append(label)
        if self._bar is None:
            elapsed = self._clock() - self._t0
            print(f"[{elapsed:4.0f} s] compiling kernel group {self.begun} of {self.total} "
                  f"({self.total - self.begun} to go): {label}", file=self._stream, flush=True)
        else:
            self._bar.update(self._task, description=", ".join(self.running), refresh=True)

    def finished(self, label: str, seconds: float) -> None:
        """A kernel group finished (in ``seconds``)."""
        self.done += 1
        self.running.remove(label)
        if self._bar is not None:
            self._bar.update(self._task, completed=self.done, description=", ".join(self.running), refresh=True)


def quiet_warnings() -> None:
    """Keep amronet's log messages below errors out of the compile's report.

    The warm-up runs every radio model and path on purpose; in each of its worker processes too (their initializer).
    """
    logging.getLogger("amronet").setLevel(logging.ERROR)


def _empty_cache(quiet: bool) -> None:
    """``--fresh``: remove the kernels compiled into amronet's cache folder."""
    from amronet import kernel_cache

    removed = kernel_cache.clear()
    if removed is None:
        mine = os.environ.get("NUMBA_CACHE_DIR")
        raise AmronetError(f"--fresh: the kernel cache is your NUMBA_CACHE_DIR ({mine}), which amronet does not "
                           "empty; remove its .nbi and .nbc files yourself, or unset NUMBA_CACHE_DIR" if mine else
                           "--fresh: amronet has no kernel cache folder of its own here (its cache home cannot be "
                           "written; numba's default __pycache__ applies): nothing to empty")
    if not quiet:
        files = "file" if removed == 1 else "files"
        print(f"emptied the kernel cache {kernel_cache.cache_folder()} ({removed} {files} removed); "
              "compiling afresh")


def cmd_compile(args: argparse.Namespace) -> int:
    """Run ``amronet compile`` (see the module docstring)."""
    from amronet.sim.warmup import task_labels, warm_up

    if args.jobs < 1:
        raise AmronetError(f"--jobs: must be >= 1, got {args.jobs}")
    if args.fresh:
        _empty_cache(args.quiet)
    report = CompileProgress(len(task_labels(args.large_runs)), sys.stderr, live=sys.stderr.isatty() and not args.quiet)
    logger = logging.getLogger("amronet")
    level = logger.level
    quiet_warnings()
    try:
        with report:
            seconds = warm_up(jobs=args.jobs, initializer=quiet_warnings,
                              started=None if args.quiet else report.started,
                              progress=None if args.quiet else report.finished, large=args.large_runs)
    except KeyboardInterrupt:  # not "nothing was written": what was compiled stays in the cache, and is sound
        print("amronet: interrupted; the kernels compiled so far stay cached, runs compile the rest",
              file=sys.stderr)
        return 130
    finally:
        logger.setLevel(level)
    print(f"amronet's kernels are compiled and cached ({seconds:.1f} s): a first run no longer compiles"
          + ("" if args.large_runs else " (one of 30 000 robots or more: amronet compile --large-runs)"))
    return 0


def add_parser(sub: Any) -> None:
    """Add ``compile`` to the subcommands ``sub``."""
    c = sub.add_parser("compile", help="compile the simulator's kernels into numba's cache (make does it once at "
                                       "installation, so that a first run does not spend tens of seconds compiling)")
    c.add_argument("--jobs", type=int, default=min(2, os.cpu_count() or 1),
                   help="worker processes (default: 2, or 1 on a one-core machine)")
    c.add_argument("--fresh", action="store_true",
                   help="first remove the kernels already compiled into amronet's cache folder (and its warm-up "
                        "notes), then compile them all again; a damaged cache entry needs no --fresh: runs "
                        "recompile it by themselves. Refused when NUMBA_CACHE_DIR (your own folder) is set")
    c.add_argument("--large-runs", action="store_true",
                   help="also compile the threaded kernels that only runs of 30 000 robots or more use (a sixth "
                        "more compiling); without it, such a run compiles them in its first step")
    c.add_argument("-q", "--quiet", action="store_true", help="print only the closing line")
    c.set_defaults(func=cmd_compile)
