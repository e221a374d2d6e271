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


def open_field_agents(**over: object):
    """Agent-assisted deployment in an open 32 m field: two agents from one base station, ``r_c`` 4 m, 400 s at most."""
    from amronet.scenario import load_scenario

    base = {
        "map": "open-32x32",
        "algorithm": {"name": "agent-assisted", "params": {"triangular": "local"}},
        "radio": {"r_c": 4.0},
        "base_stations": [{"x": 2.0, "y": 2.0, "region": [1.6, 1.6]}],
        "routers": {"count": 0},
        "agents": {"per_base": 2},
        "sim": {"dt": 0.25, "time_limit": 400.0, "record_every": 8},
    }
    return load_scenario(base, overrides=over)
