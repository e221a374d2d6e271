"""Free space of a map: the region robots can reach from given points, and clearance to the nearest wall.

Both functions treat ``OCCUPIED`` and ``UNKNOWN`` cells alike as blocked, and everything outside the map's
rectangle as blocked too.
"""

from __future__ import annotations

import numpy as np
from scipy import ndimage

from amronet.errors import MapError
from amronet.world.occupancy import OccupancyMap

__all__ = ["clearance", "reachable_free"]

_CROSS = ndimage.generate_binary_structure(2, 1)
"""4-connectivity: cells touching only at a corner are not neighbours, so diagonal walls do not leak."""


def reachable_free(omap: OccupancyMap, seeds_xy: np.ndarray) -> np.ndarray:
    """Return the free cells 4-connected to the cells holding the seed points.

    Connectivity is 4-neighbour (a cross), so a wall of one-pixel-thick diagonal steps is closed. Only cells
    of the map count: free space beyond the map's edge is never reached, even when the map's outermost cells
    are free.

    Args:
        omap: The map.
        seeds_xy: World points ``(x, y)``, shape ``(2,)`` or ``(n, 2)``; each must lie in a free cell.
            With no seed at all the result is all ``False``.

    Returns:
        Boolean array of the map's shape, ``True`` for the free cells reachable from at least one seed.

    Raises:
        MapError: A seed lies outside the map or in an occupied or unknown cell; the field is
            ``seeds[i]``.
    """
    seeds = np.asarray(seeds_xy, dtype=float).reshape(-1, 2)
    free = omap.free
    if len(seeds) == 0:
        return np.zeros(free.shape, dtype=bool)
    rows, cols = omap.world_to_cell(seeds)
    inside = omap.inside(seeds)
    for i, (x, y) in enumerate(seeds):
        if not inside[i]:
            raise MapError(
                f"seeds[{i}]",
                f"point ({x:g}, {y:g}) lies outside map '{omap.name}' (extent {_fmt(omap.extent)}); "
                "move it into free space",
            )
        if not free[rows[i], cols[i]]:
            raise MapError(
                f"seeds[{i}]",
                f"point ({x:g}, {y:g}) lies in a blocked cell (row {rows[i]}, col {cols[i]}) of map "
                f"'{omap.name}'; move it into free space",
            )
    labels, _ = ndimage.label(free, structure=_CROSS)
    wanted = np.unique(labels[rows, cols])
    return np.isin(labels, wanted)


def clearance(omap: OccupancyMap) -> np.ndarray:
    """Return each cell's distance in metres to the nearest blocked cell (occupied, unknown or off the map).

    Convention: the Euclidean distance between the cell's centre and the nearest blocked cell's centre,
    minus half a cell (``0.5 * resolution``), clipped at 0. So blocked cells have clearance 0 and a free cell
    next to a wall (or to the map's edge) has ``0.5 * resolution``: the distance from its centre to the wall's
    face. When the nearest blocked cell lies straight along a row or column this is the exact distance to
    that cell's nearest point; otherwise it overestimates it by at most ``(sqrt(2) - 1) / 2 * resolution``
    (about 0.21 cells).

    The result is computed once per map, cached in ``omap._cache`` and returned read-only.

    Args:
        omap: The map.

    Returns:
        ``float`` array of the map's shape, in metres.
    """
    if "clearance" not in omap._cache:
        padded = np.pad(omap.blocked, 1, constant_values=True)
        dist = ndimage.distance_transform_edt(~padded)[1:-1, 1:-1] * omap.resolution
        clear = np.clip(dist - 0.5 * omap.resolution, 0.0, None)
        clear.flags.writeable = False
        omap._cache["clearance"] = clear
    return omap._cache["clearance"]


def _fmt(extent: tuple[float, float, float, float]) -> str:
    """Format a map extent ``(xmin, xmax, ymin, ymax)`` for an error message."""
    xmin, xmax, ymin, ymax = extent
    return f"x {xmin:g}..{xmax:g}, y {ymin:g}..{ymax:g}"
