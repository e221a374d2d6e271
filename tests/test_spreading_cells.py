"""Self-spreading's cell flags (amronet.algorithms.self_spreading.cells): the same rings and moves, one byte read."""

import numpy as np

from amronet.algorithms.self_spreading.cells import QUIET_RING, ROOMY, Roomy, cell_flags, drive_rooms
from amronet.engine.kernel_data import grid_of
from amronet.engine.motion import drive_one
from amronet.engine.sensing import QuietRing, beam_angles, cast_rings, quiet_cells
from helpers import box_map

SENSOR_RANGE = 0.14
ROOM = Roomy(0.02, 0.045)  # the Bebot's step (0.2 m/s x 0.1 s) and body
UNLISTED = (False, 0.0, np.zeros(1, np.int64), np.zeros(1, np.int64))  # drive_rooms reads the rows


def _unlisted(near):
    return (near, *UNLISTED)


def _cluttered_map():
    rng = np.random.default_rng(7)
    walls = [(slice(int(r), int(r) + 1 + int(h)), slice(int(c), int(c) + 1 + int(w)))
             for r, c, h, w in rng.integers(0, 90, size=(40, 4)) % [90, 90, 3, 3]]
    return box_map(rows=100, cols=100, res=0.047, origin=(-0.3, 0.2), walls=walls)


def _free_points(omap, rng, n):
    rows, cols = np.nonzero(~omap.blocked)
    pick = rng.integers(len(rows), size=n)
    return np.array(omap.origin) + (np.stack([cols[pick], rows[pick]], axis=1) + rng.random((n, 2))) * omap.resolution


def _cells(omap, flags, xy, movers):
    """Each mover's byte of ``flags`` where it stands (0 off the map), as the rings hand them to the moves."""
    rows, cols = omap.world_to_cell(xy[movers])
    inside = (rows >= 0) & (rows < flags.shape[0]) & (cols >= 0) & (cols < flags.shape[1])
    return np.where(inside, flags[np.clip(rows, 0, flags.shape[0] - 1), np.clip(cols, 0, flags.shape[1] - 1)],
                    0).astype(np.uint8)


def test_the_flags_are_the_rings_and_the_moves_own_tests():
    omap = _cluttered_map()
    grid = grid_of(omap)
    flags = cell_flags(omap, grid, SENSOR_RANGE, ROOM)
    assert cell_flags(omap, grid, SENSOR_RANGE, ROOM) is flags and not flags.flags.writeable
    ring = (grid.blocked == 0) & ((grid.clear - grid.res >= SENSOR_RANGE) | (quiet_cells(omap, SENSOR_RANGE) != 0))
    room = grid.clear >= ROOM.radius + ROOM.length + 1.5 * grid.res
    np.testing.assert_array_equal((flags & QUIET_RING) != 0, ring)
    np.testing.assert_array_equal((flags & ROOMY) != 0, room)
    assert 0 < ring.mean() < 1 and 0 < room.mean() < 1 and (ring != room).any()


def test_a_ring_reads_only_bit_0_of_its_quiet_cells():
    """The flags' other bits (ROOMY) set where no beam is quiet must not make a ring read its range."""
    from numba import njit

    @njit
    def rings(grid, ring, xy, heading, radius, csr, out):
        dirs = (np.empty(out.shape[1]), np.empty(out.shape[1]))
        who = np.arange(xy.shape[0])
        cast_rings(grid, ring, who, xy, heading, radius, radius.max(), False, csr, dirs, out,
                   (0.0, np.empty(xy.shape[0] + 1, np.int64), np.empty(1, np.int64), np.empty(xy.shape[0], np.uint8)))

    omap = _cluttered_map()
    grid = grid_of(omap)
    rng = np.random.default_rng(2)
    xy = _free_points(omap, rng, 2000)
    heading = rng.uniform(-np.pi, np.pi, 2000)
    radius = np.full(2000, 0.045)
    csr = (np.zeros(2001, dtype=np.int64), np.zeros(0, dtype=np.int32), np.zeros(0))
    angles = beam_angles(12)
    quiet = quiet_cells(omap, SENSOR_RANGE)
    want = np.empty((2000, 12))
    rings(grid, QuietRing(angles, SENSOR_RANGE, quiet), xy, heading, radius, csr, want)
    for flags in (quiet | np.uint8(ROOMY), cell_flags(omap, grid, SENSOR_RANGE, ROOM)):
        got = np.empty_like(want)
        rings(grid, QuietRing(angles, SENSOR_RANGE, flags), xy, heading, radius, csr, got)
        np.testing.assert_array_equal(got, want)
    assert (want < SENSOR_RANGE).any(axis=1).mean() > 0.2  # many rings see a wall


def test_a_move_by_the_flags_is_the_move_by_the_clearance_bit_for_bit():
    """Bodies and steps larger than the flag's fall back to the clearance; everyone ends where drive_one puts them."""
    omap = _cluttered_map()
    grid = grid_of(omap)
    flags = cell_flags(omap, grid, SENSOR_RANGE, ROOM)
    rng = np.random.default_rng(3)
    n = 3000
    start = _free_points(omap, rng, n)
    heading = rng.uniform(-np.pi, np.pi, n)
    length = rng.choice([0.0, 0.01, ROOM.length, np.nextafter(ROOM.length, 1.0), 0.05], size=n)
    radius = rng.choice([0.03, ROOM.radius, np.nextafter(ROOM.radius, 1.0), 0.165], size=n)
    csr = (np.zeros(n + 1, dtype=np.int64), np.zeros(0, dtype=np.int32), np.zeros(0))
    outcomes = []
    for drive in ("flags", "clearance"):
        xy = start.copy()
        refused = np.empty(n, dtype=bool)
        distance = np.zeros(n)
        if drive == "flags":
            drive_rooms(grid, _cells(omap, flags, xy, np.arange(n)), ROOM, np.arange(n), heading, length, xy, radius,
                        False, csr, (refused, distance), _unlisted(1.0))
        else:
            for i in range(n):
                refused[i], distance[i] = drive_one(grid, i, heading[i], length[i], xy, radius, False, csr, 1.0)
        outcomes.append((xy, refused, distance))
    for got, want in zip(*outcomes, strict=True):
        np.testing.assert_array_equal(got, want)
    assert 0.02 < outcomes[0][1].mean() < 0.9  # walls refuse some moves, not all


def test_moves_among_bodies_by_the_flags_are_drive_one_in_turn_bit_for_bit():
    """With bodies the moves go one after another, each against the others as they stand: drive_one's, in order."""
    from amronet.engine.radio import UnitDisk

    omap = _cluttered_map()
    grid = grid_of(omap)
    flags = cell_flags(omap, grid, SENSOR_RANGE, ROOM)
    rng = np.random.default_rng(4)
    n = 1000
    start = _free_points(omap, rng, n)
    heading = rng.uniform(-np.pi, np.pi, n)
    radius = np.full(n, ROOM.radius)
    table = UnitDisk(0.2).update(start)
    csr = (table.indptr, table.indices, table.dist)
    movers = np.sort(rng.choice(n, size=800, replace=False))
    length = rng.choice([0.0, 0.01, ROOM.length], size=len(movers))
    near = 2.0 * ROOM.radius + 2.0 * ROOM.length
    outcomes = []
    for drive in ("flags", "clearance"):
        xy = start.copy()
        refused = np.zeros(n, dtype=bool)
        distance = np.zeros(n)
        if drive == "flags":
            drive_rooms(grid, _cells(omap, flags, xy, movers), ROOM, movers, heading, length, xy, radius, True, csr,
                        (refused, distance), _unlisted(near))
        else:
            for m, i in enumerate(movers):
                refused[i], distance[i] = drive_one(grid, i, heading[i], length[m], xy, radius, True, csr, near)
        outcomes.append((xy, refused, distance))
    for got, want in zip(*outcomes, strict=True):
        np.testing.assert_array_equal(got, want)
    refused_steps = outcomes[0][1][movers] & (length > 0)
    assert 0.1 < (outcomes[0][2] > 0).mean() and 0.05 < refused_steps.mean() < 0.8  # bodies and walls refuse some


def test_moves_from_the_links_the_rings_listed_are_the_moves_from_the_rows_bit_for_bit():
    """The rings' pass lists each mover's links within a reach; the moves read those (or the rows, if they reach
    farther) and end where drive_one puts them in turn, among bodies close enough to refuse many steps."""
    from numba import njit

    from amronet.engine.radio import UnitDisk

    @njit
    def ring_then_moves(grid, ring, movers, xy, heading, radius, csr, length, near, reach, refused, distance):
        first = np.empty(movers.shape[0] + 1, np.int64)
        edges = np.empty(csr[1].shape[0] + 1, np.int64)
        scans = np.empty((movers.shape[0], ring.angles.shape[0]))
        dirs = (np.empty(ring.angles.shape[0]), np.empty(ring.angles.shape[0]))
        cells = np.empty(movers.shape[0], np.uint8)
        cast_rings(grid, ring, movers, xy, heading, radius, radius.max(), True, csr, dirs, scans,
                   (reach, first, edges, cells))
        drive_rooms(grid, cells, ROOM, movers, heading, length, xy, radius, True, csr, (refused, distance),
                    (near, True, reach, first, edges))
        return first, edges

    omap = _cluttered_map()
    grid = grid_of(omap)
    flags = cell_flags(omap, grid, SENSOR_RANGE, ROOM)
    rng = np.random.default_rng(5)
    n = 1500
    start = _free_points(omap, rng, n)
    heading = rng.uniform(-np.pi, np.pi, n)
    radius = np.full(n, ROOM.radius)
    table = UnitDisk(1.0).update(start)
    csr = (table.indptr, table.indices, table.dist)
    movers = np.sort(rng.choice(n, size=1200, replace=False))
    ring = QuietRing(beam_angles(12), SENSOR_RANGE, flags)
    ring_reach = SENSOR_RANGE + ROOM.radius  # the list is cut at the ring's own reach at least
    short = rng.choice([0.0, 0.01, ROOM.length], size=len(movers))  # the walkers' steps
    long = rng.choice([0.0, 0.01, 0.15], size=len(movers))  # bodies beyond the list's reach refuse some of these
    # a list long enough for the moves, one cut at the ring's reach, and steps reaching past it (the rows)
    for listed_reach, length in ((2.0 * ROOM.radius + 2.0 * ROOM.length + 1e-6, short), (0.0, short), (0.0, long)):
        near = 2.0 * ROOM.radius + 2.0 * length.max()
        want_xy = start.copy()
        want_refused = np.zeros(n, dtype=bool)
        want_distance = np.zeros(n)
        for m, i in enumerate(movers):
            want_refused[i], want_distance[i] = drive_one(grid, i, heading[i], length[m], want_xy, radius, True, csr,
                                                          near)
        xy = start.copy()
        refused = np.zeros(n, dtype=bool)
        distance = np.zeros(n)
        first, edges = ring_then_moves(grid, ring, movers, xy, heading, radius, csr, length, near, listed_reach,
                                       refused, distance)
        np.testing.assert_array_equal(xy, want_xy)
        np.testing.assert_array_equal(refused, want_refused)
        np.testing.assert_array_equal(distance, want_distance)
        cut = max(listed_reach, ring_reach)
        for m in rng.choice(len(movers), size=200, replace=False):  # the list: the row's links within the reach
            i = movers[m]
            row = np.arange(table.indptr[i], table.indptr[i + 1])
            np.testing.assert_array_equal(edges[first[m]:first[m + 1]], row[table.dist[row] <= cut])
        refused_steps = want_refused[movers] & (length > 0)
        assert 0.05 < refused_steps.mean() < 0.8  # bodies and walls refuse some
    listed = np.diff(first)
    assert listed.mean() < 0.3 * np.diff(table.indptr)[movers].mean() and listed.max() > 1  # short lists
