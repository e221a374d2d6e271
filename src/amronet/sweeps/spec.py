"""Sweep files: a base scenario, a grid (and/or a list) of overrides, and seeds — parsed and validated up front.

A sweep is one YAML file::

    name: rc-vs-triangular
    description: coverage of self-spreading vs r_c, local and global triangular rule
    base: self-spreading-6x6          # a preset name, a scenario file (relative to this file) or a mapping
    overrides: {sim.time_limit: 60}   # applied to every point (optional)
    grid:                             # the cartesian product of these lists (optional)
      radio.r_c: [0.8, 1.0, 1.2]
      algorithm.params.triangular: [local, global]
    points:                           # explicit points, run after the grid's (optional)
      - {radio.r_c: 2.0, routers.count: 10}
    seeds: 5                          # seeds seed_start .. seed_start + 4 for every point, or a list [3, 7, 11]
    seed_start: 0

Keys are the dotted paths of ``--set`` (:func:`amronet.scenario.apply_overrides`). Without ``grid`` and
``points`` the sweep has one point, the base. The file is read as scenario files are (:mod:`amronet.yaml_loading`:
``1e-3`` is a number, a key given twice an error). Every point is validated as a whole scenario before anything
runs: unknown keys (in the sweep file or in a point), empty grids, a seed count of 0, a seed outside
``[0, 2**63 - 1]`` (the range the result store's 64-bit integer column holds) or a bad value raise
:class:`~amronet.errors.ScenarioError` with one line naming the field, and nothing is written.

The resource guard (:mod:`amronet.limits`) counts the points before the grid is expanded: a sweep whose points and
runs would not fit in the memory available is refused, and one of more than ``MAX_SWEEP_POINTS`` points or
``MAX_SWEEP_RUNS`` runs unless acknowledged (``force=True``, ``amronet sweep --force``). Every point's runs are
checked as a run is (:func:`amronet.sim.guard.check_scenario`: bodies that fit, memory, steps); the workers run
them unacknowledged, so a point whose runs would take absurdly long is refused whatever the sweep's ``force``.
Then every
distinct start is set up once (:func:`~amronet.sweeps.check.check_points`): a map that is neither a built-in
name nor a file, a base station off the map or in a wall, or robots that do not fit their start region is the
same one-line error, naming the sweep key (``grid``, ``points[i]``, ``overrides`` or ``base``) and the point.

Switching the algorithm: when the overrides of a point (its own or the sweep's ``overrides``) set
``algorithm.name`` to another algorithm than the base's, the base's ``algorithm.params`` are dropped first,
since they belong to the base's algorithm; the new algorithm starts from its defaults, and ``algorithm.params``
or ``algorithm.params.KEY`` given in the overrides apply on top. So ``grid: {algorithm.name: [self-spreading,
dssa]}`` over a self-spreading base keeps the base's parameters for self-spreading and runs DSSA with its own
defaults.
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from pydantic import BaseModel, ConfigDict, Field, StrictInt, ValidationError, model_validator

from amronet import limits
from amronet.errors import ScenarioError
from amronet.scenario import Scenario, load_scenario, to_scenario_error
from amronet.sim.guard import check_scenario
from amronet.sweeps.check import check_points, owner_key
from amronet.sweeps.identity import resolve_scenario, scenario_hash
from amronet.yaml_loading import load_yaml

__all__ = ["MAX_SEED", "MAX_SEEDS", "Point", "Sweep", "SweepSpec", "load_sweep", "sweep_from_spec"]

MAX_SEED = 2**63 - 1
"""The largest seed: the result store keeps seeds in a signed 64-bit SQLite integer."""
MAX_SEEDS = 1_000_000
"""The most seeds a sweep may give as a count (a larger count is a typo, and would not fit in memory)."""


class SweepSpec(BaseModel):
    """A sweep file, validated (see the module docstring)."""

    model_config = ConfigDict(extra="forbid", frozen=True)

    name: str = Field(min_length=1)
    """The sweep's name (its key in the result store)."""
    description: str = ""
    """One line saying what the sweep measures."""
    base: Any
    """A preset name, a scenario file path (relative to the sweep file) or an inline scenario mapping."""
    overrides: dict[str, Any] = Field(default_factory=dict)
    """``--set`` keys applied to every point."""
    grid: dict[str, list[Any]] | None = None
    """Keys and lists of values: every combination is a point."""
    points: list[dict[str, Any]] | None = None
    """Explicit points (mappings of keys to values), after the grid's."""
    seeds: Any
    """A number of seeds (``>= 1``; seeds ``seed_start, seed_start + 1, ...``) or a list of distinct seeds."""
    seed_start: StrictInt = Field(default=0, ge=0)
    """The first seed when ``seeds`` is a count."""

    @model_validator(mode="after")
    def _check(self) -> SweepSpec:
        if not isinstance(self.base, str | dict) or (isinstance(self.base, str) and not self.base.strip()):
            raise ValueError("@base@must be a preset name, a scenario file path or a scenario mapping")
        if self.grid is not None:
            if not self.grid:
                raise ValueError("@grid@is empty; give at least one KEY: [values] (or drop grid and use points)")
            for key, values in self.grid.items():
                if not values:
                    raise ValueError(f"@grid.{key}@is an empty list; give at least one value")
        if self.points is not None and not self.points:
            raise ValueError("@points@is an empty list; give at least one mapping of KEY: value (or drop it)")
        seeds = self.seeds
        if isinstance(seeds, bool) or not isinstance(seeds, int | list):
            raise ValueError(f"@seeds@must be a number of seeds (>= 1) or a list of seeds, got {seeds!r}")
        if isinstance(seeds, int):
            if seeds < 1:
                raise ValueError(f"@seeds@must be at least 1 (got {seeds}); it is the number of seeded runs per point")
            if seeds > MAX_SEEDS:
                raise ValueError(f"@seeds@{seeds} seeds per point is more than {MAX_SEEDS}; give a smaller count")
            if self.seed_start > MAX_SEED:
                raise ValueError(f"@seed_start@{self.seed_start} is above the largest seed 2**63 - 1 = {MAX_SEED}; "
                                 "give a smaller seed_start")
            if self.seed_start + seeds - 1 > MAX_SEED:
                raise ValueError(f"@seeds@seed_start {self.seed_start} + {seeds} seeds runs past the largest seed "
                                 f"2**63 - 1 = {MAX_SEED}; lower seed_start or the count")
        else:
            if not seeds:
                raise ValueError("@seeds@is an empty list; give at least one seed")
            if any(isinstance(s, bool) or not isinstance(s, int) or s < 0 for s in seeds):
                raise ValueError("@seeds@a list of seeds must hold integers >= 0")
            big = next((s for s in seeds if s > MAX_SEED), None)
            if big is not None:
                raise ValueError(f"@seeds@seed {big} is above the largest seed 2**63 - 1 = {MAX_SEED}; "
                                 "give seeds in [0, 2**63 - 1]")
            if len(set(seeds)) != len(seeds):
                raise ValueError("@seeds@lists a seed twice; give distinct seeds")
            if self.seed_start:
                raise ValueError("@seed_start@only goes with a number of seeds, not with a list")
        return self

    def seed_list(self) -> list[int]:
        """The seeds every point runs with."""
        if isinstance(self.seeds, int):
            return list(range(self.seed_start, self.seed_start + self.seeds))
        return list(self.seeds)


@dataclass(frozen=True)
class Point:
    """One point of a sweep.

    Attributes:
        index: Position in the sweep (grid points first, then the explicit points).
        overrides: The swept keys' values at this point (without the sweep's fixed ``overrides``).
        scenario: The fully resolved scenario (:func:`~amronet.sweeps.identity.resolve_scenario`).
        hash: Its hash (the store's key together with the seed).
    """

    index: int
    overrides: dict[str, Any]
    """``--set`` keys applied to every point."""
    scenario: dict[str, Any]
    hash: str


@dataclass(frozen=True)
class Sweep:
    """A validated sweep: its spec, its points and its seeds.

    Attributes:
        spec: The sweep file's content.
        points: Every point, validated and resolved.
        seeds: The seeds each point runs with.
        keys: The swept keys, in the order they first appear.
    """

    spec: SweepSpec
    points: list[Point]
    """Explicit points (mappings of keys to values), after the grid's."""
    seeds: list[int]
    """Seeds per point: a count (``seed_start`` .. ``seed_start + n - 1``) or a list."""
    keys: list[str]

    @property
    def name(self) -> str:
        """The sweep's name."""
        return self.spec.name

    def runs(self) -> list[tuple[Point, int]]:
        """Every (point, seed), point-major; a run repeated by two identical points is listed once."""
        seen: set[tuple[str, int]] = set()
        out = []
        for p in self.points:
            for s in self.seeds:
                if (p.hash, s) not in seen:
                    seen.add((p.hash, s))
                    out.append((p, s))
        return out


def _base_scenario(spec: SweepSpec, base_dir: str | None) -> Scenario:
    base = spec.base
    try:
        if isinstance(base, dict):
            sc = load_scenario(base)
            return sc.model_copy(update={"base_dir": base_dir}) if base_dir else sc
        candidate = Path(base_dir) / base if base_dir and not Path(base).is_absolute() else Path(base)
        return load_scenario(candidate if candidate.is_file() else base)
    except ScenarioError as exc:
        raise ScenarioError(f"base: {exc.field}" if exc.field else "base", exc.message) from None


def _point(base: Scenario, fixed: dict[str, Any], overrides: dict[str, Any], where: str, index: int) -> Point:
    try:
        merged = {**fixed, **overrides}  # switching algorithm.name drops the base's params (apply_overrides)
        sc = base.with_overrides(merged) if merged else base
        resolved = resolve_scenario(sc)
    except ScenarioError as exc:
        key = owner_key(exc.field, list(overrides))
        if key is not None:
            value = f" (at {key} = {overrides[key]!r})" if key != exc.field else ""
            raise ScenarioError(f"{where}.{exc.field}" if where else exc.field, exc.message + value) from None
        key = owner_key(exc.field, list(fixed))
        raise ScenarioError(f"overrides.{exc.field}" if key is not None else f"base: {exc.field}",
                            exc.message) from None
    try:  # the workers run every point unacknowledged: so is the check
        check_scenario(sc, acknowledge="or run that point alone with amronet run --force (a sweep's runs are "
                                       "never forced)")
    except ScenarioError as exc:
        if where:
            shown = ", ".join(f"{k} = {v!r}" for k, v in overrides.items())
            raise ScenarioError(f"{where}.{exc.field}", f"{exc.message} (at point {index}: {shown})") from None
        key = owner_key(exc.field, list(fixed))
        raise ScenarioError(f"overrides.{exc.field}" if key is not None else f"base: {exc.field}",
                            exc.message) from None
    return Point(index=index, overrides=dict(overrides), scenario=resolved, hash=scenario_hash(resolved))


def _check_size(spec: SweepSpec, force: bool) -> None:
    """Refuse, before the grid is expanded, a sweep too large for the memory or, unacknowledged, for patience."""
    grid = math.prod(len(v) for v in spec.grid.values()) if spec.grid else 0
    points = grid + len(spec.points or []) or 1
    seeds = spec.seeds if isinstance(spec.seeds, int) else len(spec.seeds)
    runs = points * seeds
    field = "grid" if grid > len(spec.points or []) else "points"
    what = (f"a grid of {' x '.join(str(len(v)) for v in spec.grid.values())} = {limits.format_count(grid)} points"
            if field == "grid" else f"{points} points")
    limits.check_memory(points * limits.BYTES_PER_SWEEP_POINT + runs * limits.BYTES_PER_SWEEP_RUN, field,
                        f"{what} with {seeds} seed{'s' if seeds != 1 else ''} each",
                        "split the sweep or give fewer values")
    limits.check_work(points, limits.MAX_SWEEP_POINTS, field, what, "split the sweep or give fewer values", force)
    limits.check_work(runs, limits.MAX_SWEEP_RUNS, "seeds",
                      f"{limits.format_count(points)} points x {seeds} seeds = {limits.format_count(runs)} runs",
                      "give fewer seeds or points", force)


def sweep_from_spec(spec: SweepSpec | dict[str, Any], base_dir: str | Path | None = None,
                    check_start: bool = True, force: bool = False) -> Sweep:
    """Validate a sweep given as a spec or a mapping and expand its points.

    Args:
        spec: The sweep.
        base_dir: Folder that a relative ``base`` path and an inline base's relative map path are taken from.
        check_start: Also set up every distinct start once (:func:`~amronet.sweeps.check.check_points`: the
            maps load, the base stations and robots fit); ``False`` checks the fields only.
        force: Acknowledge a sweep of more than ``limits.MAX_SWEEP_POINTS`` points or ``MAX_SWEEP_RUNS`` runs.

    Raises:
        ScenarioError: The sweep or one of its points is invalid, or the resource guard refuses it (see the
            module docstring); one line naming the field.
    """
    if not isinstance(spec, SweepSpec):
        if not isinstance(spec, dict):
            raise ScenarioError("sweep", f"must be a mapping of fields, got {type(spec).__name__}")
        try:
            spec = SweepSpec.model_validate(spec)
        except ValidationError as exc:
            raise to_scenario_error(exc, model=SweepSpec) from None
    _check_size(spec, force)
    folder = str(Path(base_dir).resolve()) if base_dir is not None else None
    base = _base_scenario(spec, folder)
    fixed = _point(base, spec.overrides, {}, "", -1)  # the fixed overrides alone, so their errors name them
    combos: list[tuple[dict[str, Any], str]] = []
    if spec.grid:
        keys = list(spec.grid)
        for values in itertools.product(*(spec.grid[k] for k in keys)):
            combos.append((dict(zip(keys, values, strict=True)), "grid"))
    for i, item in enumerate(spec.points or []):
        combos.append((item, f"points[{i}]"))
    if not combos:
        combos.append(({}, ""))
    points = [_point(base, spec.overrides, o, where, k) for k, (o, where) in enumerate(combos)]
    if check_start:
        check_points([(p, where) for p, (_, where) in zip(points, combos, strict=True)], fixed, spec.overrides,
                     spec.seed_list()[0])
    keys = list(dict.fromkeys(k for o, _ in combos for k in o))
    return Sweep(spec=spec, points=points, seeds=spec.seed_list(), keys=keys)


def load_sweep(source: str | Path | dict[str, Any], force: bool = False) -> Sweep:
    """Load, validate and expand a sweep file (or mapping).

    Args:
        source: Path of a sweep YAML file, or its content as a mapping.
        force: Acknowledge a sweep of more points or runs than the resource guard lets run unacknowledged.

    Returns:
        The sweep.

    Raises:
        ScenarioError: The file cannot be read or the sweep is invalid; one line naming the field.
    """
    if isinstance(source, dict):
        return sweep_from_spec(source, force=force)
    path = Path(source)
    if not path.is_file():
        raise ScenarioError("sweep", f"no sweep file {str(path)!r}; give the path of a sweep YAML")
    try:
        text = path.read_text()
    except (OSError, UnicodeDecodeError) as exc:
        raise ScenarioError("sweep", f"cannot read {str(path)!r}: {exc}") from None
    data = load_yaml(text, "sweep", repr(str(path)))
    if data is None:
        raise ScenarioError("sweep", f"{str(path)!r} is empty; give name, base and seeds (and grid or points)")
    return sweep_from_spec(data, base_dir=path.resolve().parent, force=force)
