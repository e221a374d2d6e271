"""Maps: the occupancy grid, loading ROS map_server files, built-in maps, reachable free space; agents' paths.

The names below load on first use, so that a light module (:mod:`amronet.world.names`: the built-in maps' names)
can be imported without NumPy, SciPy or the image reader -- a scenario naming an unknown map is refused at once.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from amronet.world.builtin import MapInfo, list_builtin_maps, load_builtin_map, resolve_map
    from amronet.world.loading import load_map_yaml
    from amronet.world.names import BUILTIN_MAPS
    from amronet.world.occupancy import FREE, OCCUPIED, UNKNOWN, OccupancyMap
    from amronet.world.space import clearance, reachable_free
    from amronet.world.trajectories import AgentPaths, load_trajectories

_HOMES = {
    "BUILTIN_MAPS": "names",
    "FREE": "occupancy",
    "OCCUPIED": "occupancy",
    "UNKNOWN": "occupancy",
    "AgentPaths": "trajectories",
    "MapInfo": "builtin",
    "OccupancyMap": "occupancy",
    "clearance": "space",
    "list_builtin_maps": "builtin",
    "load_builtin_map": "builtin",
    "load_map_yaml": "loading",
    "load_trajectories": "trajectories",
    "reachable_free": "space",
    "resolve_map": "builtin",
}
"""Each public name and the module of :mod:`amronet.world` that defines it."""

__all__ = [
    "BUILTIN_MAPS",
    "FREE",
    "OCCUPIED",
    "UNKNOWN",
    "AgentPaths",
    "MapInfo",
    "OccupancyMap",
    "clearance",
    "list_builtin_maps",
    "load_builtin_map",
    "load_map_yaml",
    "load_trajectories",
    "reachable_free",
    "resolve_map",
]


def __getattr__(name: str) -> Any:
    home = _HOMES.get(name)
    if home is None:
        raise AttributeError(f"module 'amronet.world' has no attribute {name!r}")
    value = getattr(importlib.import_module(f"amronet.world.{home}"), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted({*globals(), *_HOMES})
