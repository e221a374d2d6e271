"""Small hand-made maps for unit tests."""

import numpy as np

from amronet.world.occupancy import FREE, OCCUPIED, OccupancyMap


def box_map(rows=100, cols=100, res=0.05, origin=(0.0, 0.0), walls=()) -> OccupancyMap:
    """An open box with a one-cell border; ``walls`` are (row_slice, col_slice) pairs to occupy."""
    cells = np.full((rows, cols), FREE, dtype=np.int8)
    cells[0, :] = cells[-1, :] = cells[:, 0] = cells[:, -1] = OCCUPIED
    for rs, cs in walls:
        cells[rs, cs] = OCCUPIED
    return OccupancyMap(name="box", resolution=res, origin=origin, cells=cells)


def diagonal_wall_map(n=60, res=0.05) -> OccupancyMap:
    """A box split by a one-pixel wall along the diagonal (8-connected, so 4-connected free space is split)."""
    cells = np.full((n, n), FREE, dtype=np.int8)
    cells[0, :] = cells[-1, :] = cells[:, 0] = cells[:, -1] = OCCUPIED
    idx = np.arange(n)
    cells[idx, idx] = OCCUPIED
    return OccupancyMap(name="diag", resolution=res, origin=(0.0, 0.0), cells=cells)
