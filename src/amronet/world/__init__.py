"""Maps: the occupancy grid, loading ROS map_server files, built-in maps, reachable free space; agents' paths."""

from amronet.world.builtin import BUILTIN_MAPS, MapInfo, list_builtin_maps, load_builtin_map, resolve_map
from amronet.world.loading import load_map_yaml
from amronet.world.occupancy import FREE, OCCUPIED, UNKNOWN, OccupancyMap
from amronet.world.space import clearance, reachable_free
from amronet.world.trajectories import AgentPaths, load_trajectories

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
