"""Compile amronet's kernels ahead of the first run: a few short runs that reach every compiled kernel.

amronet's hot loops are numba kernels compiled on first use and kept in numba's on-disk cache (``cache=True``),
so the first run in a fresh environment pays the compiling (tens of seconds) and every later one loads the
machine code in milliseconds. :func:`warm_up` moves that cost to the installation (``make`` calls ``amronet
compile``): it runs, for a few simulated seconds, one scenario per algorithm, explorer, drop rule, walk rule and
radio model that amronet registers, a batch of the batchable algorithms, runs with faults and packet loss, the
signal map and a static pattern's placement, so that a user's first run finds every kernel it uses compiled; with
``large``, one small run with the threaded kernels of large runs too (:mod:`amronet.threads`: only runs of 30 000
robots or more use them; otherwise such a run compiles them first). With several jobs, each task runs in one worker
process, and the workers compile each kernel once between them (:mod:`amronet.kernel_cache_lock`); a task waits
while one of its algorithm runs in another worker, if a task of another group can start instead
(:func:`run_in_pool`). The cases are built by the algorithms themselves
(:meth:`~amronet.algorithms.base.Controller.warm_ups`, from their registries: a new explorer, drop rule or radio
model is warmed up without a change here).

Where ``amronet compile`` did not run (a ``pip install``, a new version of the kernels' source), a sweep or a
figure on several local workers runs the :data:`COMMON` cases first, spread over its workers
(:func:`warm_up_if_cold`): otherwise each worker compiles the same kernels at the same time. A note in the cache
folder (:func:`amronet.kernel_cache.mark_compiled`) says which warm-up finished for this version of the kernels.

The runs' results are thrown away; they change nothing but numba's cache (the same machine code a first run would
have compiled), so results are bit for bit the same with or without a warm-up.
"""

from __future__ import annotations

import contextlib
import multiprocessing
import signal
import time
from collections.abc import Callable, Collection, Sequence
from concurrent.futures import FIRST_COMPLETED, Executor, Future, ProcessPoolExecutor, wait
from dataclasses import dataclass, fields, replace
from typing import Any

import numpy as np

from amronet.algorithms.base import ALGORITHMS, WarmUp
from amronet.engine.propagation import LinkBudget
from amronet.engine.radio import make_medium
from amronet.errors import AmronetError
from amronet.kernel_cache import compiled, mark_compiled
from amronet.patterns import place
from amronet.scenario import load_scenario
from amronet.signals import sigint_deferred
from amronet.sim.batch import run_seeds
from amronet.sim.simulation import Simulation
from amronet.threads import threads_from
from amronet.world.builtin import FLOOR_CORNERS, resolve_map

__all__ = ["COMMON", "WarmupCase", "WarmupError", "run_in_pool", "task_labels", "warm_up", "warm_up_if_cold",
           "warmup_cases"]

COMMON: tuple[str, ...] = (
    "explorer frontier", "algorithm agent-assisted", "algorithm self-spreading", "algorithm potential-field",
    "algorithm dssa", "batch self-spreading", "batch potential field", "static patterns",
)
"""The warm-up cases whose kernels common runs share: every algorithm with its defaults, the frontier explorer
(the figures' agents), batches (the figures' runs) and the static patterns (Fig. 5)."""

_ALL_STAMP, _COMMON_STAMP = "all", "common"


class WarmupError(AmronetError):
    """A warm-up task raised an exception, or its worker process died.

    Args:
        label: The task's label (its kernel group).
        exc: What it raised.
    """

    def __init__(self, label: str, exc: BaseException) -> None:
        why = (str(exc).strip().splitlines() or [""])[0]
        super().__init__(f"kernel group {label!r} failed ({type(exc).__name__}{': ' + why if why else ''}); "
                         "runs still work and compile the kernels they use")
        self.label = label


def _after_ctrl_c(exc: BaseException | None) -> bool:
    """Whether ``exc`` was raised while handling a ``KeyboardInterrupt`` (its cause or context, at any depth)."""
    seen: set[int] = set()
    while exc is not None and id(exc) not in seen:
        if isinstance(exc, KeyboardInterrupt):
            return True
        seen.add(id(exc))
        exc = exc.__cause__ or exc.__context__
    return False


@dataclass(frozen=True)
class WarmupCase(WarmUp):
    """One warm-up run (an algorithm's :class:`~amronet.algorithms.base.WarmUp`), and how to run it.

    Attributes:
        algorithm: The name of the algorithm that lists it (in :data:`~amronet.algorithms.base.ALGORITHMS`).
    """

    algorithm: str = ""

    def run(self) -> None:
        """Run the case (the result is discarded)."""
        scenario = load_scenario(self.preset, {"sim.time_limit": self.seconds, **self.overrides})
        with threads_from(0) if self.threaded else contextlib.nullcontext():
            if len(self.seeds) > 1:
                run_seeds(scenario, list(self.seeds))
            else:
                Simulation(scenario, self.seeds[0], step=self.step).run()


def _figures_agents(case: WarmupCase) -> WarmupCase:
    """The frontier explorer as the figures' agents run it (Fig. 7's four corner bases, their step).

    The networks meet (triangle routers drive to their goals), the frontier repaints what its network covers and
    agents check their release spots within 40 simulated seconds. The longest chain of kernels: it starts first.
    """
    bases = [{"x": x, "y": y, "region": [1.6, 1.6]} for x, y in FLOOR_CORNERS]
    return replace(case, overrides={**case.overrides, "sim.dt": 0.25, "base_stations": bases}, seconds=40.0,
                   first=True)


_FIGURES: dict[str, Callable[[WarmupCase], WarmupCase]] = {"explorer frontier": _figures_agents}
"""An algorithm's case the figures run in a setting of their own, by label: the figures' variant replaces it."""


def _signal_map() -> None:
    """The signal layer's kernel (snapshots, animations, the replay page and ``amronet radio-map``)."""
    omap = resolve_map("obstacles-6x6")
    medium = make_medium("multi-wall", LinkBudget(r_c=1.0, exponent=2.0, wall_db=6.9), omap)
    medium.signal_dbm(omap, np.array([[3.0, 3.0]]))


def _patterns() -> None:
    """The static patterns' kernels (``amronet patterns``, Fig. 5's placed counts): the r-strip's connectors."""
    place("r-strip", (8.0, 8.0), 2.0)


_TASKS: dict[int, tuple[str, Callable[[], None]]] = {
    -1: ("signal map", _signal_map), -2: ("static patterns", _patterns)}
"""The warm-up's tasks that are not runs: label and function by key (negative; a run's key is its index in
:func:`warmup_cases`)."""


def warmup_cases() -> list[WarmupCase]:
    """The warm-up runs: every registered algorithm's own (:meth:`~amronet.algorithms.base.Controller.warm_ups`).

    Each algorithm lists the runs that reach its kernels (its rules, explorers, drop rules, walks, radio models, its
    fast step, batches); the figures' variants replace the cases they run in a setting of their own (:data:`_FIGURES`).
    """
    cases = []
    for name, controller in ALGORITHMS.items():
        for spec in controller.warm_ups():
            case = WarmupCase(**{f.name: getattr(spec, f.name) for f in fields(spec)}, algorithm=name)
            cases.append(_FIGURES[case.label](case) if case.label in _FIGURES else case)
    return cases


def _tasks(large: bool = False) -> list[tuple[str, int]]:
    """Every warm-up task as ``(label, key)``, in the order they start.

    The longest chains first (``first``), then the tasks that are not runs (:data:`_TASKS`: the signal map, the
    static patterns), then the other cases (key: their index in :func:`warmup_cases`). The cases of large runs
    (``threaded``: the kernels only runs of :data:`~amronet.threads.MIN_ITEMS` robots or more use, a sixth of the
    compiling) only with ``large``.
    """
    cases = warmup_cases()
    keep = [k for k, c in enumerate(cases) if large or not c.threaded]
    order = [k for k in keep if cases[k].first] + list(_TASKS) + [k for k in keep if not cases[k].first]
    return [(cases[k].label if k >= 0 else _TASKS[k][0], k) for k in order]


def task_labels(large: bool = False) -> list[str]:
    """The labels of the warm-up's tasks (the kernel groups ``amronet compile`` reports), in the order they start.

    Args:
        large: With the cases of large runs (``amronet compile --large-runs``).
    """
    return [label for label, _ in _tasks(large)]


def _run_case(k: int) -> float:
    t = time.perf_counter()
    if k < 0:
        _TASKS[k][1]()
    else:
        warmup_cases()[k].run()
    return time.perf_counter() - t



def _worker_start(initializer: Callable[..., object] | None, initargs: tuple[Any, ...]) -> None:
    """Start a warm-up worker: it ignores ``SIGINT``, then runs ``initializer(*initargs)``.

    A terminal's Ctrl-C reaches the workers too; :func:`warm_up` ends them itself, at once.
    """
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    if hasattr(signal, "pthread_sigmask"):  # blocked since its start (:func:`run_in_pool`); now ignored
        signal.pthread_sigmask(signal.SIG_UNBLOCK, {signal.SIGINT})
    if initializer is not None:
        initializer(*initargs)


def _stop_now(pool: ProcessPoolExecutor, grace_s: float = 0.5) -> None:
    """End ``pool``'s workers now, whatever they compile (``SIGTERM``, ``SIGKILL`` after ``grace_s``), not after it."""
    processes = list((getattr(pool, "_processes", None) or {}).values())
    pool.shutdown(wait=False, cancel_futures=True)
    for process in processes:
        with contextlib.suppress(ValueError, OSError):  # already ended
            process.terminate()
    deadline = time.monotonic() + grace_s
    for process in processes:
        process.join(max(0.0, deadline - time.monotonic()))
        if process.is_alive():
            process.kill()
            process.join()


def _pick(waiting: Sequence[tuple[str, int]], busy: Collection[str], group: Callable[[int], str] | None) -> int:
    """The index in ``waiting`` (the next task last) of the task to start.

    The next one of a group that no running task is of (``busy``), else the next one.
    """
    if group is not None:
        for i in range(len(waiting) - 1, -1, -1):
            if group(waiting[i][1]) not in busy:
                return i
    return len(waiting) - 1


def run_in_pool(pool: Executor, tasks: Sequence[tuple[str, int]], slots: int, run: Callable[[int], float],
                started: Callable[[str], None] | None = None,
                progress: Callable[[str, float], None] | None = None,
                group: Callable[[int], str] | None = None) -> None:
    """Run ``run(key)`` for each ``(label, key)`` in ``tasks`` on ``pool``, at most ``slots`` at a time, in order.

    A task is handed to the pool only when one of the ``slots`` is free, so the ones handed over are the ones
    running: ``started(label)`` is called as each is handed over, ``progress(label, seconds)`` as each finishes
    (``seconds``: what ``run`` returned). With ``group`` (a task's group by its key: the warm-up's, its
    algorithm), a task of a group that a running task is of waits while a later one of another group can start:
    tasks of one algorithm share most of their kernels, and a worker would wait while the other one compiles them
    (:mod:`amronet.kernel_cache_lock`).

    Raises:
        WarmupError: The first task that raised an exception (or whose worker died), with that exception.
    """
    waiting = list(reversed(tasks))
    running: dict[Future[float], tuple[str, str | None]] = {}
    while waiting or running:
        while waiting and len(running) < slots:
            label, key = waiting.pop(_pick(waiting, {busy for _, busy in running.values()}, group))
            if started is not None:
                started(label)
            with sigint_deferred():  # a worker started now starts with it blocked (:func:`_worker_start`)
                running[pool.submit(run, key)] = (label, None if group is None else group(key))
        finished, _ = wait(running, return_when=FIRST_COMPLETED)
        for future in finished:
            label, _ = running.pop(future)
            try:
                seconds = future.result()
            except Exception as exc:  # the task's, or the pool's (a worker that died): one line, with its group
                raise WarmupError(label, exc) from exc
            if progress is not None:
                progress(label, seconds)


def warm_up(jobs: int = 1, progress: Callable[[str, float], None] | None = None,
            only: Collection[str] | None = None, initializer: Callable[..., object] | None = None,
            initargs: tuple[Any, ...] = (), started: Callable[[str], None] | None = None, large: bool = False
            ) -> float:
    """Run every warm-up case (:func:`warmup_cases`), the signal map and the static patterns; return the wall time.

    Args:
        jobs: Worker processes (1: in this process). Kernels compiled by one worker are written to the cache, so
            the workers share what they compile once it is written.
        progress: Called with each case's label and its wall time as it finishes.
        only: The labels of the cases to run (default: all but those of large runs, see ``large``); :data:`COMMON`
            names the kernels common runs share.
        initializer: With several jobs, what each worker process runs first, with ``initargs`` (as for
            :class:`~concurrent.futures.ProcessPoolExecutor`).
        initargs: Its arguments.
        started: Called with each case's label as it starts (:func:`run_in_pool`: with several jobs, as a worker
            takes it).
        large: Also the cases of large runs (``threaded``: the kernels that only runs of
            :data:`~amronet.threads.MIN_ITEMS` robots or more use; without it, such a run compiles them first).

    Raises:
        ValueError: ``only`` names a case that does not exist.
        WarmupError: A case failed (the kernels compiled until then stay cached).
    """
    tasks = _tasks(large or only is not None)
    if only is not None:
        unknown = sorted(set(only) - {label for label, _ in tasks})
        if unknown:
            raise ValueError(f"no warm-up case {unknown}")
        tasks = [(label, k) for label, k in tasks if label in only]
    t0 = time.perf_counter()
    if jobs <= 1:
        for label, k in tasks:
            if started is not None:
                started(label)
            try:
                seconds = _run_case(k)
            except Exception as exc:
                if _after_ctrl_c(exc):  # a library's error for a Ctrl-C (numba stopped mid-compile): Ctrl-C's
                    raise
                raise WarmupError(label, exc) from exc
            if progress is not None:
                progress(label, seconds)
    else:
        pool = ProcessPoolExecutor(max_workers=jobs, mp_context=multiprocessing.get_context("spawn"),
                                   initializer=_worker_start, initargs=(initializer, initargs))
        try:
            groups = {k: case.algorithm for k, case in enumerate(warmup_cases())}
            run_in_pool(pool, tasks, jobs, _run_case, started, progress, group=lambda k: groups.get(k, str(k)))
        except BaseException:  # Ctrl-C, a failure: what the workers compiled so far stays cached
            _stop_now(pool)
            raise
        pool.shutdown()
    if only is None or set(only) >= set(COMMON):  # noted for warm_up_if_cold
        mark_compiled(_ALL_STAMP if only is None else _COMMON_STAMP)
    return time.perf_counter() - t0


def warm_up_if_cold(workers: int, runs: int, announce: Callable[[], None] | None = None,
                    initializer: Callable[..., object] | None = None, initargs: tuple[Any, ...] = ()) -> float | None:
    """Compile the :data:`COMMON` kernels across the workers first if this version of them was never compiled.

    Called before ``runs`` runs on ``workers`` local processes; "never compiled": no warm-up of them finished
    (:func:`~amronet.kernel_cache.compiled`; ``make`` runs ``amronet compile`` when it installs amronet). Without
    it, with a cold cache, every worker compiles the same kernels at the same time, each as slowly as one alone
    (``reproduce paper`` on two cores with an empty cache, in one sitting: 142.5 s, 92.5–99.9 s with this first; the
    machine's speed moved such times by a quarter from hour to hour, 95–125 s on 2026-11-26). Here each case
    runs in one worker, the longest first, so the workers compile different kernels, mostly, and load each other's
    from the cache. A failure here is no error: the runs compile what they use, as without it.

    Args:
        workers: The local worker processes the runs will use.
        runs: The runs about to start (a single run compiles only what it uses, in one process: no warm-up).
        announce: Called before the warm-up starts (a progress bar's note).
        initializer: What each of the warm-up's worker processes runs first, with ``initargs``.
        initargs: Its arguments.

    Returns:
        The warm-up's wall time in seconds, or ``None`` if none ran.
    """
    if workers < 2 or runs < 2 or compiled(_ALL_STAMP, _COMMON_STAMP) is not False:
        return None
    if announce is not None:
        announce()
    try:
        return warm_up(jobs=workers, only=COMMON, initializer=initializer, initargs=initargs)
    except Exception:  # the runs compile what they use, and report their own errors
        return None
