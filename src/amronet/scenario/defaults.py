"""Defaults that depend on the rest of the scenario: the algorithm's own, and start regions that hold their robots.

* **The algorithm's defaults** (its declaration's
  :attr:`~amronet.algorithms.declaration.Declaration.scenario_defaults`): a scenario that
  leaves a field out gets its algorithm's value instead of the schema's. Agent-assisted deployment, whose agents
  release the routers, starts with no free routers (``routers.count: 0``), three agents per base station and the
  range of the paper's agent-assisted setups (``radio.r_c: 6``; a radio given by ``threshold_dbm`` keeps the
  range that implies). A field given keeps its value.
* **Start regions** (``base_stations[i].region`` left out): the smallest square, on a 0.1 m grid and at least the
  schema's 1 m x 1 m, that holds the base station's routers and agents in open floor around its reference node
  (:func:`fitted_side`). Where 1 m x 1 m holds them the region is what it always was. Walls next to the base
  station can still take part of a region; the set-up then says which region would hold the robots there
  (:mod:`amronet.sim.assemble`).

The scenario remembers which fields took such a default, and an override computes them again
(:meth:`Scenario.with_overrides <amronet.scenario.schema.Scenario.with_overrides>`, a sweep's point): a point
with another algorithm or more agents gets the defaults that fit it.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any

from amronet.algorithms.declaration import ALGORITHMS, declaration_of
from amronet.engine.robot_models import ROBOT_MODELS

if TYPE_CHECKING:
    from amronet.scenario.schema import RobotRef, Scenario

__all__ = ["DEFAULT_REGION_M", "fill_start_regions", "fitted_side", "with_algorithm_defaults", "without"]

DEFAULT_REGION_M = 1.0
"""Side of the default start region when that holds the robots (the paper's 1 m x 1 m base region, 5.2)."""
_GRID_M = 0.1
"""Fitted sides are multiples of this."""
_SPACING = 1.05
"""Lattice spacing over the widest body's diameter: slack for the start packing's own lattice."""
_GIVEN_BY = {"radio.r_c": ("threshold_dbm",)}
"""A default field that another field also fixes: given too when one of these keys of its section is (not null)."""


def _given(section: dict[str, Any], path: str) -> bool:
    """Whether a section of raw data gives the field at ``path`` (or one that fixes it, :data:`_GIVEN_BY`)."""
    key = path.split(".")[1]
    return key in section or any(section.get(k) is not None for k in _GIVEN_BY.get(path, ()))


def with_algorithm_defaults(data: Any) -> tuple[Any, list[str]]:
    """Scenario data with the fields its algorithm sets by default filled in where the data leaves them out.

    Args:
        data: Raw scenario data (a mapping; anything else is returned as it is, for the schema to refuse).

    Returns:
        ``(data, paths)``: the data (a new mapping when a field was filled) and every field that some algorithm
        sets by default and the data leaves out (filled, or left to the schema's default): another algorithm
        would set them otherwise.
    """
    if not isinstance(data, dict):
        return data, []
    algorithm = data.get("algorithm", {})
    name = algorithm.get("name", "self-spreading") if isinstance(algorithm, dict) else None
    own = declaration_of(name).scenario_defaults if isinstance(name, str) and name in ALGORITHMS else {}
    out, unset = dict(data), []
    for path in sorted({p for n in ALGORITHMS for p in declaration_of(n).scenario_defaults}):
        section = out.get(path.split(".")[0], {})
        if not isinstance(section, dict) or _given(section, path):
            continue  # given, or a section the schema refuses
        unset.append(path)
        if path in own:
            out[path.split(".")[0]] = {**section, path.split(".")[1]: own[path]}
    return out, unset


def without(data: dict[str, Any], paths: frozenset[str]) -> dict[str, Any]:
    """``data`` (a scenario's :meth:`~amronet.scenario.schema.Scenario.to_dict`) less the fields at ``paths``.

    Paths are dotted, list items by index (``base_stations.0.region``); the data is changed in place and returned.
    """
    for path in paths:
        *parents, last = path.split(".")
        node: Any = data
        for part in parents:
            node = node[int(part)] if isinstance(node, list) else node.get(part, {})
        if isinstance(node, dict):
            node.pop(last, None)
    return data


def _radius(ref: RobotRef) -> float | None:
    """A robot's body radius, ``None`` for an unknown name (the set-up names the field)."""
    model = ROBOT_MODELS.get(ref) if isinstance(ref, str) else ref
    return None if model is None else float(model.radius)


def _lattice_count(side: float, spacing: float, keep_out: float) -> int:
    """Points of a square lattice from a corner of a ``side`` square centred on the base, ``keep_out`` from it."""
    m = int(math.floor(side / spacing + 1e-9)) + 1
    near = [x for x in (k * spacing - 0.5 * side for k in range(m)) if abs(x) < keep_out]
    return m * m - sum(1 for x in near for y in near if math.hypot(x, y) < keep_out)


def fitted_side(count: int, radius: float, base_radius: float) -> float:
    """The side of the smallest square start region that holds ``count`` bodies of ``radius`` around a base node.

    The bodies stand on a square lattice of ``2.1 radius`` from a corner of the square, which is centred on the
    base's reference node (of ``base_radius``), none on it; the side is the smallest multiple of 0.1 m, at least
    :data:`DEFAULT_REGION_M`, whose lattice has ``count`` points. The start placement (random draws, then a
    packing of its own) placed every such count tried in open floor: 1-30 agents, 10-400 routers, mixed.
    """
    if count <= 0 or radius <= 0:
        return DEFAULT_REGION_M
    spacing = 2.0 * radius * _SPACING
    below = (math.ceil(math.sqrt(count)) - 1) * spacing  # fewer than sqrt(count) points a row hold too few
    side = max(DEFAULT_REGION_M, round(math.floor(below / _GRID_M) * _GRID_M, 6))
    while _lattice_count(side, spacing, base_radius + radius) < count:
        side = round(side + _GRID_M, 6)
    return side


def fill_start_regions(scenario: Scenario) -> list[str]:
    """Give every base station that has no ``region`` one that holds its routers and agents (:func:`fitted_side`).

    Routers are dealt round-robin over the base stations (none with ``routers.start: uniform``); every body is
    taken as wide as the widest present, so routers drawn at random leave room for the agents placed after them.

    Returns:
        The paths of the regions filled (``base_stations.0.region``, ...).
    """
    filled = []
    bases = scenario.base_stations
    routers = scenario.routers.count if scenario.routers.start == "base" else 0
    router_r, agent_r = _radius(scenario.routers.robot), _radius(scenario.agents.robot)
    for i, base in enumerate(bases):
        if "region" in base.model_fields_set:
            continue
        filled.append(f"base_stations.{i}.region")
        mine, agents = len(range(i, routers, len(bases))), scenario.agents.per_base
        radii, base_r = [r for n, r in ((mine, router_r), (agents, agent_r)) if n], _radius(base.robot)
        if not radii or None in radii or base_r is None:
            continue
        side = fitted_side(mine + agents, max(r for r in radii if r is not None), base_r)
        object.__setattr__(base, "region", (side, side))
    return filled
