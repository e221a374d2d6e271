"""Optima kept in a result store like runs: solved once, loaded after, keyed by a hash of the problem.

A run is kept under its scenario hash (:mod:`amronet.sweeps.identity`); an optimum is kept under the same kind of
hash of its *problem* (:func:`optimum_problem`): the map (a built-in map's name or a map file's absolute path, and
its content's digest, so an edited map file is a new problem), the base stations and the routers' robot as a run
resolves them, the radio with every default spelt out (``{}`` and ``{model: unit-disk}`` are one problem), the
candidate spacing, the coverage sample, the seed of the shadowing field (only for radios that draw one), and the
solver's settings: the time limit, the coarse-lattice switch and the last phase's solver (named only when it is not
HiGHS, the default, so the keys of answers kept before there was a choice stay): with a time limit that is reached,
the answer depends on them. :data:`KEY_VERSION` is part of the key, so a search that finds different answers can
retire the old ones.

:func:`find_or_load_optimum` loads the stored answer when there is one and otherwise solves and stores it, in one
transaction as every finished run (:mod:`amronet.sweeps.store_optima`): a figure stopped half way keeps every
optimum it finished.

Example:
    >>> import tempfile, pathlib
    >>> store = pathlib.Path(tempfile.mkdtemp()) / "results.sqlite"
    >>> a = find_or_load_optimum("obstacles-6x6", [(-2.5, -2.5)], 3.0, 1.5, time_limit=20, store=store)
    >>> b = find_or_load_optimum("obstacles-6x6", [(-2.5, -2.5)], 3.0, 1.5, time_limit=20, store=store)
    >>> (a.count, a.from_store), (b.count, b.from_store)
    ((4, False), (4, True))
"""

from __future__ import annotations

import time
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

from amronet.errors import AmronetError, ScenarioError
from amronet.optimum.instance import build_instance, check_lengths, instance_scenario, scenario_option_error
from amronet.optimum.report import Optimum
from amronet.optimum.solve import check_solver, check_time_limit, find_optimum
from amronet.sim.assemble import medium_needs_rng
from amronet.sweeps.identity import resolve_scenario, scenario_hash
from amronet.sweeps.store import ResultStore
from amronet.world.occupancy import OccupancyMap

__all__ = ["KEY_VERSION", "find_or_load_optimum", "optimum_key", "optimum_problem"]

KEY_VERSION = 1
"""Part of every optimum's key: raise it when the search changes what it finds, so stored answers are not reused."""

SAMPLE = "reachable cell centres"
"""The coverage sample (:mod:`amronet.optimum.instance`), named in the key."""


def optimum_problem(map_ref: str, bases: Sequence[tuple[float, float]], r_c: float, spacing: float, *,
                    radio: dict[str, Any] | None = None, seed: int = 0, time_limit: float = 60.0,
                    coarse: bool | None = None, solver: str = "highs") -> dict[str, Any]:
    """The optimum problem as plain data: what decides its answer (see the module docstring).

    Args:
        map_ref: A built-in map's name or a ROS map_server YAML path.
        bases: Base-station positions ``(x, y)`` (m).
        r_c: The radio's range (m).
        spacing: The candidate lattice's spacing (m).
        radio: Radio fields beyond ``r_c``; ``None``: the unit disk.
        seed: Seed of the radio's shadowing field (kept only for radios that draw one).
        time_limit: Seconds for the search.
        coarse: The coarse-lattice switch of :func:`~amronet.optimum.solve.find_optimum`.
        solver: The last phase's solver (``highs`` or ``cp-sat``).

    Raises:
        AmronetError: Bad input, one line naming the option.
    """
    check_time_limit(time_limit)
    check_solver(solver)
    check_lengths(r_c, spacing)
    try:
        scenario = instance_scenario(str(map_ref), bases, r_c, radio)
        resolved = resolve_scenario(scenario)
    except ScenarioError as exc:  # MapError too
        raise scenario_option_error(exc) from None
    return {"map": resolved["map"], "base_stations": resolved["base_stations"], "radio": resolved["radio"],
            "router_robot": resolved["routers"]["robot"], "spacing_m": float(spacing), "sample": SAMPLE,
            "seed": int(seed) if medium_needs_rng(scenario) else None,
            "solver": {"time_limit_s": float(time_limit), "coarse": coarse, "key_version": KEY_VERSION,
                       **({} if solver == "highs" else {"engine": solver})}}


def optimum_key(problem: dict[str, Any]) -> str:
    """The problem's key in a result store: SHA-256 of its canonical JSON and of its map's content."""
    return scenario_hash(problem)


def find_or_load_optimum(map_ref: str | OccupancyMap, bases: Sequence[tuple[float, float]], r_c: float,
                         spacing: float, *, radio: dict[str, Any] | None = None, seed: int = 0,
                         time_limit: float = 60.0, coarse: bool | None = None, solver: str = "highs",
                         store: str | Path | None = None,
                         instance: bool = False, log: Callable[[str], None] | None = None) -> Optimum:
    """:func:`~amronet.optimum.solve.find_optimum` through a result store: loaded when solved before, else solved.

    Args:
        map_ref: A built-in map's name or a ROS map_server YAML path (a map object only without ``store``).
        bases: Base-station positions ``(x, y)`` (m).
        r_c: The radio's range (m).
        spacing: The candidate lattice's spacing (m).
        radio: Radio fields beyond ``r_c``; ``None``: the unit disk.
        seed: Seed of the radio's shadowing field.
        time_limit: Seconds for the search.
        coarse: Search the lattice of twice the spacing first (``None``: on large lattices).
        solver: The last phase's solver, ``highs`` or ``cp-sat`` (OR-Tools, an optional extra).
        log: Called with a line per phase (progress), or with where a loaded answer came from.
        store: The result store (SQLite path, created when missing); ``None``: solve, keep nothing.
        instance: Attach the instance to a loaded answer too (built again, for the picture).

    Returns:
        The answer; its ``from_store`` says whether it was loaded.

    Raises:
        AmronetError: Bad input (one line naming the option); the store cannot be used (``--store``); a map given
            as an object with a store (it has no name to key it by).
    """
    if store is None:
        return find_optimum(map_ref, bases, r_c, spacing, radio=radio, seed=seed, time_limit=time_limit,
                            coarse=coarse, solver=solver, log=log)
    if isinstance(map_ref, OccupancyMap):
        raise AmronetError("--store: an optimum of a map given as an object cannot be kept in a store; give the "
                           "map's name or its YAML file")
    problem = optimum_problem(map_ref, bases, r_c, spacing, radio=radio, seed=seed, time_limit=time_limit,
                              coarse=coarse, solver=solver)
    key = optimum_key(problem)
    with ResultStore(store) as rs:
        doc = rs.stored_optimum(key)
    if doc is not None:
        opt = Optimum.from_dict(doc)
        opt.from_store = True
        if instance:
            opt.instance = build_instance(map_ref, bases, r_c, spacing, radio=radio, seed=seed)
        if log is not None:
            log(f"loaded from the store {store} (solved before, {opt.seconds.get('total', 0.0):.1f} s)")
        return opt
    t0 = time.perf_counter()
    opt = find_optimum(map_ref, bases, r_c, spacing, radio=radio, seed=seed, time_limit=time_limit, coarse=coarse,
                       solver=solver, log=log)
    with ResultStore(store) as rs:
        rs.record_optimum(key, problem, opt.to_dict(), wall_time_s=round(time.perf_counter() - t0, 3))
    return opt
