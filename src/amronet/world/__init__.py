"""Maps: the occupancy grid, loading ROS map_server files, built-in maps and reachable free space."""

from amronet.world.builtin import BUILTIN_MAPS, MapInfo, list_builtin_maps, load_builtin_map, resolve_map
from amronet.world.loading import load_map_yaml
from amronet.world.occupancy import FREE, OCCUPIED, UNKNOWN, OccupancyMap
from amronet.world.space import clearance, reachable_free

__all__ = [
    "BUILTIN_MAPS",
    "FREE",
    "OCCUPIED",
    "UNKNOWN",
    "MapInfo",
    "OccupancyMap",
    "clearance",
    "list_builtin_maps",
    "load_builtin_map",
    "load_map_yaml",
    "reachable_free",
    "resolve_map",
]
