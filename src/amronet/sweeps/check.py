"""Check that every point of a sweep can start: its map loads, its base stations and robots fit on it.

Validating a point's fields (:mod:`amronet.sweeps.spec`) does not load its map; :func:`check_points` does, before
anything runs or anything is written. It sets up each distinct start (map, base stations, robots, radio,
algorithm, step; not the time limit or the stopping rules) once, as a run would
(:class:`~amronet.sim.Simulation` with the sweep's first seed), loading each map once, so a missing map, a base
station off the map or too many robots for the start region is one line naming the sweep key and the point
instead of a sweep of failed runs.
"""

from __future__ import annotations

import re
from collections.abc import Sequence
from typing import Any

from amronet.errors import ScenarioError
from amronet.scenario import load_scenario
from amronet.sim import Simulation
from amronet.sim.assemble import load_scenario_map
from amronet.sweeps.identity import canonical_json

__all__ = ["check_points", "owner_key"]

_NOT_AT_START = ("time_limit", "record_every", "coverage_target", "coverage_method", "stop_when_settled")
"""``sim`` fields a run reads only after it has started: two points that differ only in these start alike."""


def owner_key(field: str, keys: Sequence[str]) -> str | None:
    """The override key among ``keys`` that set ``field`` (``base_stations[0]`` is ``base_stations.0``)."""
    dotted = re.sub(r"\[(\d+)\]", r".\1", field)
    for key in keys:
        if dotted == key or dotted.startswith(key + ".") or key.startswith(dotted + "."):
            return key
    return None


def _start_key(resolved: dict[str, Any]) -> str:
    data = {k: v for k, v in resolved.items() if k not in ("name", "description")}
    data["sim"] = {k: v for k, v in resolved.get("sim", {}).items() if k not in _NOT_AT_START}
    return canonical_json(data)


def _values(overrides: dict[str, Any]) -> str:
    return ", ".join(f"{k} = {v!r}" for k, v in overrides.items())


def _start(resolved: dict[str, Any], seed: int, maps: dict[str, Any]) -> None:

    scenario = load_scenario(resolved)
    ref = resolved["map"]
    if ref not in maps:
        maps[ref] = load_scenario_map(scenario)
    Simulation(scenario, seed, omap=maps[ref])


def check_points(points: Sequence[tuple[Any, str]], base: Any, fixed: dict[str, Any], seed: int) -> None:
    """Set up every distinct start of ``points`` once, as a run with ``seed`` would.

    Args:
        points: ``(point, where)`` pairs: a :class:`~amronet.sweeps.spec.Point` and the sweep key it comes from
            (``"grid"``, ``"points[2]"``, or ``""`` for the base alone).
        base: The base with the sweep's ``overrides`` as a :class:`~amronet.sweeps.spec.Point`: started only to
            tell, when a point fails, whether the base already fails.
        fixed: The sweep's ``overrides`` (applied to every point).
        seed: The seed to place the robots with (the sweep's first).

    Raises:
        ScenarioError: A point cannot start; one line naming the sweep key and the point:
            ``grid.map: ...`` when a swept key's value is wrong, ``grid: point 3 (routers.count = 3000):
            base_stations[0].region: ...`` when the point's combination is, ``base: ...`` or ``overrides...``
            when the base with the sweep's overrides cannot start either.
    """
    maps: dict[str, Any] = {}
    seen: set[str] = set()
    for point, where in points:
        key = _start_key(point.scenario)
        if key in seen:
            continue
        seen.add(key)
        try:
            _start(point.scenario, seed, maps)
        except ScenarioError as exc:
            raise _blame(exc, point, where, base, fixed, seed, maps) from None


def _blame(exc: ScenarioError, point: Any, where: str, base: Any, fixed: dict[str, Any], seed: int,
           maps: dict[str, Any]) -> ScenarioError:
    if where and owner_key(exc.field, list(point.overrides)) is not None:
        return ScenarioError(f"{where}.{exc.field}", f"{exc.message} (at point {point.index}: "
                                                     f"{_values(point.overrides)})")
    if where and point.overrides:
        try:
            _start(base.scenario, seed, maps)
        except ScenarioError as base_exc:
            exc = base_exc
        else:
            field = f"{exc.field}: " if exc.field else ""
            return ScenarioError(where, f"point {point.index} ({_values(point.overrides)}): {field}{exc.message}")
    if owner_key(exc.field, list(fixed)) is not None:
        return ScenarioError(f"overrides.{exc.field}", exc.message)
    return ScenarioError(f"base: {exc.field}" if exc.field else "base", exc.message)
