"""Compile amronet's kernels ahead of the first run: a few short runs that reach every compiled kernel.

amronet's hot loops are numba kernels compiled on first use and kept in numba's on-disk cache (``cache=True``),
so the first run in a fresh environment pays the compiling (tens of seconds) and every later one loads the
machine code in milliseconds. :func:`warm_up` moves that cost to the installation (``make`` calls ``amronet
compile``): it runs, for a few simulated seconds, one scenario per algorithm, explorer, drop rule, walk rule and
radio model that amronet registers, a batch of the batchable algorithms, runs with faults and packet loss, the
signal map and a static pattern's placement, and one small run with the threaded kernels of large runs
(:mod:`amronet.threads`), so that a user's first run finds every kernel it uses compiled. The cases are built
from the registries: a new explorer, drop rule or radio model is warmed up without a change here.

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
import time
from collections.abc import Callable, Collection
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from amronet.algorithms.base import ALGORITHMS
from amronet.algorithms.drops.base import DROP_RULES
from amronet.algorithms.explorers.base import EXPLORERS
from amronet.algorithms.walks import WALKS
from amronet.engine.propagation import LinkBudget
from amronet.engine.radio import MEDIA, make_medium
from amronet.kernel_cache import compiled, mark_compiled
from amronet.patterns import place
from amronet.scenario import load_scenario
from amronet.sim.batch import run_seeds
from amronet.sim.loop import Simulation, StepKind
from amronet.threads import threads_from
from amronet.world.builtin import FLOOR_CORNERS, resolve_map

__all__ = ["BASE_PRESETS", "COMMON", "WarmupCase", "warm_up", "warm_up_if_cold", "warmup_cases"]

BASE_PRESETS: dict[str, str] = {
    "agent-assisted": "agent-assisted-office",
    "self-spreading": "self-spreading-obstacles-6x6",
    "potential-field": "potential-field-obstacles-6x6",
    "dssa": "dssa-obstacles-6x6",
}
"""The preset each registered algorithm is warmed up on (a test checks that every algorithm has one)."""

COMMON: tuple[str, ...] = (
    "explorer frontier", "algorithm agent-assisted", "algorithm self-spreading", "algorithm potential-field",
    "algorithm dssa", "batch self-spreading", "batch potential field", "static patterns",
)
"""The warm-up cases whose kernels common runs share: every algorithm with its defaults, the frontier explorer
(the figures' agents), batches (the figures' runs) and the static patterns (Fig. 5)."""

_ALL_STAMP, _COMMON_STAMP = "all", "common"

_SECONDS = 3.0
"""Simulated seconds per warm-up run: enough for every phase of a step to run a few times."""


@dataclass(frozen=True)
class WarmupCase:
    """One warm-up run: a preset with overrides, for a few simulated seconds.

    Attributes:
        label: What the case warms up, for the report.
        preset: The built-in scenario.
        overrides: Dotted-path fields to replace.
        seeds: One seed: a single run; several: one batch of them (the batched kernels).
        seconds: Simulated seconds.
        threaded: Run the kernels that large runs run on several threads (:mod:`amronet.threads`).
        step: The loop's step (``reference``: phase by phase, as the runs a compiled step does not cover).
        first: One of the cases that compile the longest chains of kernels (tens of seconds): with several jobs
            they start first, so that the other jobs compile the rest meanwhile (74 s instead of 87 s on two cores).
    """

    label: str
    preset: str
    overrides: dict[str, Any] = field(default_factory=dict)
    seeds: tuple[int, ...] = (1,)
    seconds: float = _SECONDS
    threaded: bool = False
    step: StepKind = "compiled"
    first: bool = False

    def run(self) -> None:
        """Run the case (the result is discarded)."""
        scenario = load_scenario(self.preset, {"sim.time_limit": self.seconds, **self.overrides})
        with threads_from(0) if self.threaded else contextlib.nullcontext():
            if len(self.seeds) > 1:
                run_seeds(scenario, list(self.seeds))
            else:
                Simulation(scenario, self.seeds[0], step=self.step).run()


_FIGURES_AGENTS = WarmupCase(
    "explorer frontier", BASE_PRESETS["agent-assisted"],
    {"algorithm.params.explorer": "frontier", "sim.dt": 0.25,
     "base_stations": [{"x": x, "y": y, "region": [1.6, 1.6]}
                       for x, y in FLOOR_CORNERS]},
    seconds=40.0, first=True)
"""The frontier explorer as the figures' agents run it (Fig. 7's four corner bases, their step): the networks meet
(triangle routers drive to their goals), the frontier repaints what its network covers and agents check their release
spots within 40 simulated seconds. The longest chain of kernels: it starts first."""


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
    """The warm-up runs, built from the registries (every algorithm, explorer, drop rule, walk and radio model)."""
    aa, ss = BASE_PRESETS["agent-assisted"], BASE_PRESETS["self-spreading"]
    cases = [WarmupCase(f"algorithm {name}", BASE_PRESETS[name]) for name in ALGORITHMS]
    cases += [_FIGURES_AGENTS if name == "frontier" else
              WarmupCase(f"explorer {name}", aa, {"algorithm.params.explorer": name}) for name in EXPLORERS]
    cases += [WarmupCase(f"drop rule {name}", aa, {"algorithm.params.drop_rule": name,
                                                   "algorithm.params.explorer": "frontier"}) for name in DROP_RULES]
    cases += [WarmupCase(f"walk {name}", ss, {"algorithm.params.walk": name}) for name in WALKS]
    cases += [WarmupCase(f"radio {name}", ss, {"radio.model": name}) for name in MEDIA]
    cases += [WarmupCase(f"radio {name}, agents", aa, {"radio.model": name, "algorithm.params.explorer": "frontier"})
              for name in MEDIA]
    cases += [
        WarmupCase("packet loss, link-quality stop rule", ss,
                   {"radio.model": "multi-wall", "radio.packet_loss": True, "radio.shadowing_db": 4.0,
                    "algorithm.params.stop_rule": "link-quality", "algorithm.params.triangle_rule": "link-quality"}),
        WarmupCase("faults and relocation", aa,
                   {"faults": [{"at": 1.0, "routers": 0.5}], "algorithm.params.repair": "relocate",
                    "algorithm.params.explorer": "frontier", "sim.coverage_target": "off"}),
        # two networks that meet within seconds: triangle routers drive to their goal points, in the compiled step
        # and phase by phase (as in agent-assisted runs with several base stations)
        *(WarmupCase(f"triangular deployment, {step} step", "self-spreading-6x6",
                     {"base_stations": [{"x": -1.2, "y": 0.0, "region": [0.6, 0.6]},
                                        {"x": 1.2, "y": 0.0, "region": [0.6, 0.6]}]}, seconds=20.0, step=step)
          for step in ("compiled", "reference")),
        WarmupCase("batch self-spreading", "self-spreading-6x6", seeds=(1, 2)),
        WarmupCase("batch potential field", "potential-field-6x6", seeds=(1, 2)),
        WarmupCase("large runs: the threaded kernels", "self-spreading-6x6", threaded=True, first=True),
    ]
    return cases


def _tasks() -> list[tuple[str, int]]:
    """Every warm-up task as ``(label, key)``, in the order they start.

    The longest chains first (``first``), then the tasks that are not runs (:data:`_TASKS`: the signal map, the
    static patterns), then the other cases (key: their index in :func:`warmup_cases`).
    """
    cases = warmup_cases()
    order = [k for k, c in enumerate(cases) if c.first] + list(_TASKS) + [k for k, c in enumerate(cases) if not c.first]
    return [(cases[k].label if k >= 0 else _TASKS[k][0], k) for k in order]


def _run_case(k: int) -> float:
    t = time.perf_counter()
    if k < 0:
        _TASKS[k][1]()
    else:
        warmup_cases()[k].run()
    return time.perf_counter() - t


def warm_up(jobs: int = 1, progress: Callable[[str, float], None] | None = None,
            only: Collection[str] | None = None, initializer: Callable[..., object] | None = None,
            initargs: tuple[Any, ...] = ()) -> float:
    """Run every warm-up case (:func:`warmup_cases`), the signal map and the static patterns; return the wall time.

    Args:
        jobs: Worker processes (1: in this process). Kernels compiled by one worker are written to the cache, so
            the workers share what they compile once it is written.
        progress: Called with each case's label and its wall time as it finishes.
        only: The labels of the cases to run (default: all); :data:`COMMON` names the kernels common runs share.
        initializer: With several jobs, what each worker process runs first, with ``initargs`` (as for
            :class:`~concurrent.futures.ProcessPoolExecutor`).
        initargs: Its arguments.

    Raises:
        ValueError: ``only`` names a case that does not exist.
    """
    tasks = _tasks()
    if only is not None:
        unknown = sorted(set(only) - {label for label, _ in tasks})
        if unknown:
            raise ValueError(f"no warm-up case {unknown}")
        tasks = [(label, k) for label, k in tasks if label in only]
    t0 = time.perf_counter()
    if jobs <= 1:
        for label, k in tasks:
            seconds = _run_case(k)
            if progress is not None:
                progress(label, seconds)
    else:
        with ProcessPoolExecutor(max_workers=jobs, mp_context=multiprocessing.get_context("spawn"),
                                 initializer=initializer, initargs=initargs) as pool:
            for (label, _), seconds in zip(tasks, pool.map(_run_case, [k for _, k in tasks]), strict=True):
                if progress is not None:
                    progress(label, seconds)
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
