"""Coverage under a margin-decided radio, kept as a running union of the nodes' cells: exact, and little work.

:class:`~amronet.engine.coverage_heard.HeardCells` keeps per coverage area the union of the cells heard from the
nodes of the last call (:mod:`amronet.engine.coverage_union`). Whatever the nodes do from call to call, its mask is
the one a fresh :func:`~amronet.engine.hearing.heard_cells` over all the nodes marks; a node that joins decides
only the cells still uncovered, one that leaves only the cells it marked first, and those only by the nodes that
joined after it.
"""

from __future__ import annotations

import functools

import numpy as np
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from amronet.engine.cell_boxes import BLOCK
from amronet.engine.coverage import CoverageArea
from amronet.engine.coverage_heard import HeardCells
from amronet.engine.coverage_union import BYTES_PER_CELL, _blocks_holding, block_grid, full_window
from amronet.engine.propagation import LinkBudget
from amronet.engine.radio import RadioMedium, make_medium
from amronet.world.builtin import resolve_map

MAP = "hospital_section"  # a real floor plan: rooms, corridors and their walls
NO_OWNER = np.zeros((0, 0), np.int32)
NO_KEYS = np.zeros(0, np.int32)


@functools.cache
def _world() -> tuple[CoverageArea, np.ndarray]:
    """The map's coverage area and a pool of 24 free points spread over its west end."""
    omap = resolve_map(MAP)
    area = CoverageArea(omap, omap.free)
    rows, cols = np.nonzero(omap.free[:, :400])
    pick = np.random.default_rng(5).choice(len(rows), 24, replace=False)
    return area, omap.cell_centres(rows[pick], cols[pick])


@functools.cache
def _medium(shadowing_db: float) -> RadioMedium:
    omap = _world()[0].omap
    return make_medium("multi-wall", LinkBudget(r_c=1.5, exponent=2.0, wall_db=6.9, shadowing_db=shadowing_db),
                       omap, rng=np.random.default_rng(3))


def _afresh(medium: RadioMedium, area: CoverageArea, xy: np.ndarray) -> np.ndarray:
    """One :func:`heard_cells` over every node of ``xy`` from an empty mask: the reference."""
    out = np.zeros(area.mask.shape, dtype=bool)
    medium.kernels.heard_cells(np.ascontiguousarray(xy, dtype=float).reshape(-1, 2), NO_KEYS, area.mask,
                               medium.heard.cells(area.omap), float(medium.reach), out, NO_OWNER,
                               full_window(out.shape), medium.hearing.plain(), block_grid(out.shape))
    return out


_OPS = ("add", "drop", "move", "same", "other", "twin", "all move")


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(shadowing=st.sampled_from([0.0, 4.0]), room=st.sampled_from(["none", "one union", "plenty"]),
       start=st.sets(st.integers(0, 23), max_size=20),
       ops=st.lists(st.tuples(st.sampled_from(_OPS), st.integers(0, 23), st.integers(-3, 3)), min_size=3,
                    max_size=16))
def test_covered_equals_a_fresh_pass_over_every_node_at_every_call(shadowing, room, start, ops):
    area, pool = _world()
    medium = _medium(shadowing)
    cells = area.mask.size * BYTES_PER_CELL
    budget = {"none": 0, "one union": cells + cells // 2, "plenty": 4 * cells}[room]
    heard = HeardCells(medium.hearing, medium.kernels, cache_bytes=budget)
    pool = pool.copy()
    nodes = sorted(start)
    for op, i, shift in ops:
        xy = pool[nodes]
        if op == "add":  # a node joins (or, already there, stays)
            nodes = sorted({*nodes, i})
            xy = pool[nodes]
        elif op == "drop" and nodes:  # a node leaves: failed, released, or moving on
            nodes.remove(nodes[i % len(nodes)])
            xy = pool[nodes]
        elif op == "move":  # a node moves a little
            pool[i] += 0.1 * shift
            xy = pool[nodes]
        elif op == "all move":  # every node moves (most of the union starts again)
            pool[nodes] += 0.05 * shift
            xy = pool[nodes]
        elif op == "other":  # the connected part of the nodes, asked about between two calls of all of them
            xy = pool[nodes[: len(nodes) // 2]]
        elif op == "twin":  # two nodes at one point
            xy = pool[[*nodes, i, i]]
        got = heard.covered(area, xy, medium.reach)
        np.testing.assert_array_equal(got, _afresh(medium, area, xy))
        unions = [u for memo in heard.areas.values() for u in memo.unions]
        assert len(unions) <= 2
        assert sum(u.nbytes for u in unions) <= budget


class _Work:
    """A :func:`heard_cells` that counts the (node, cell) pairs it may decide: in reach, in its window, in its
    mask and not covered yet."""

    def __init__(self, kernel, omap, reach: float) -> None:
        self.kernel, self.reach, self.calls, self.pairs = kernel, reach, 0, 0
        self.cy = omap.origin[1] + (np.arange(omap.shape[0]) + 0.5) * omap.resolution
        self.cx = omap.origin[0] + (np.arange(omap.shape[1]) + 0.5) * omap.resolution

    def __call__(self, xy, keys, mask, grid, reach, covered, owner, window, hearing, blocks):
        i0, i1, j0, j1 = window
        open_ = mask[i0:i1 + 1, j0:j1 + 1] & ~covered[i0:i1 + 1, j0:j1 + 1]
        for x, y in xy:
            near = np.hypot(self.cx[None, j0:j1 + 1] - x, self.cy[i0:i1 + 1, None] - y) <= reach
            self.pairs += int(np.count_nonzero(open_ & near))
        self.calls += 1
        return self.kernel(xy, keys, mask, grid, reach, covered, owner, window, hearing, blocks)

    def take(self) -> int:
        pairs, self.pairs = self.pairs, 0
        return pairs


def _counted(shadowing_db: float) -> tuple[CoverageArea, np.ndarray, RadioMedium, _Work, HeardCells]:
    """The world, a medium, and coverage whose kernel counts the work it is asked to do."""
    area, pool = _world()
    medium = _medium(shadowing_db)
    work = _Work(medium.kernels.heard_cells, area.omap, medium.reach)
    return area, pool, medium, work, HeardCells(medium.hearing, medium.kernels._replace(heard_cells=work))


def test_a_node_decides_only_the_cells_it_changes():
    area, pool, medium, work, heard = _counted(0.0)
    routers = pool[:12]
    heard.covered(area, routers, medium.reach)
    built = work.take()
    base = heard.covered(area, routers, medium.reach)
    assert work.take() == 0  # nothing changed: no cell decided
    # a router put down next to one that covers its surroundings: only what the others leave uncovered is decided
    near = np.vstack([routers, routers[4] + 0.05])
    xx, yy = np.meshgrid(work.cx - near[-1, 0], work.cy - near[-1, 1])
    in_reach = area.mask & (np.hypot(xx, yy) <= medium.reach)
    for _ in range(3):  # it joins the union at once, and stays
        np.testing.assert_array_equal(heard.covered(area, near, medium.reach), _afresh(medium, area, near))
    assert work.take() == np.count_nonzero(in_reach & ~base)
    assert 10 * np.count_nonzero(in_reach & ~base) < np.count_nonzero(in_reach)  # not its whole box, as before
    # a router that leaves: only the cells it marked first are decided again, by the routers that came after it
    union = next(iter(heard.areas.values())).unions[0]
    owned = int(np.count_nonzero(union.owner == union.members[tuple(near[4])]))
    rest = np.delete(near, 4, axis=0)
    np.testing.assert_array_equal(heard.covered(area, rest, medium.reach), _afresh(medium, area, rest))
    redone = work.take()
    assert 0 < redone <= owned * (len(near) - 5)  # by the routers 5, 6, ... and the new one: those after it
    assert redone < built // 4  # far less than deciding the routers afresh


def test_two_sets_asked_about_in_turn_keep_a_union_each():
    area, pool, medium, work, heard = _counted(0.0)
    every, linked = pool[:14], pool[:9]  # all the nodes, and those connected to a base
    for _ in range(4):
        for xy in (every, linked):
            np.testing.assert_array_equal(heard.covered(area, xy, medium.reach), _afresh(medium, area, xy))
    work.take()
    calls = work.calls
    for _ in range(3):
        for xy in (every, linked):
            np.testing.assert_array_equal(heard.covered(area, xy, medium.reach), _afresh(medium, area, xy))
    assert work.calls == calls and work.take() == 0  # each set finds its own union as it left it
    # the union's calls (owners, cells to decide again) and the moving nodes' share one compiled version
    assert len(medium.kernels.heard_cells.signatures) == 1


def test_a_second_set_of_nodes_starts_from_the_first_ones_union():
    area, pool, medium, work, heard = _counted(4.0)
    every, linked = pool[:16], pool[:12]  # all the nodes, and those connected to a base
    for xy in (every, linked):
        np.testing.assert_array_equal(heard.covered(area, xy, medium.reach), _afresh(medium, area, xy))
    built = work.take()
    np.testing.assert_array_equal(heard.covered(area, every, medium.reach), _afresh(medium, area, every))
    assert len(next(iter(heard.areas.values())).unions) == 2  # a union of its own
    # it copied the connected nodes' union: only the four nodes it adds decide cells, not all sixteen afresh
    assert 0 < work.take() < built // 3
    for xy in (linked, every, linked):
        np.testing.assert_array_equal(heard.covered(area, xy, medium.reach), _afresh(medium, area, xy))
    assert work.take() == 0  # each set finds its own union as it left it


def test_a_union_interrupted_half_way_is_dropped_not_kept_wrong():
    area, pool = _world()
    medium = _medium(0.0)
    calls = []

    def interrupted(*args):
        calls.append(1)
        if len(calls) == 2:  # the second pass: the nodes that leave, decided again
            raise KeyboardInterrupt
        return medium.kernels.heard_cells(*args)

    heard = HeardCells(medium.hearing, medium.kernels._replace(heard_cells=interrupted))
    nodes = np.vstack([pool[:10], pool[0] + 0.05])  # the last one covers again what the first covered first
    heard.covered(area, nodes, medium.reach)
    try:
        heard.covered(area, nodes[1:], medium.reach)
    except KeyboardInterrupt:
        pass
    assert len(calls) == 2 and next(iter(heard.areas.values())).unions == []
    np.testing.assert_array_equal(heard.covered(area, nodes[1:], medium.reach), _afresh(medium, area, nodes[1:]))


def test_areas_share_the_room_the_least_recently_used_union_goes_first():
    area, pool = _world()
    half = area.mask.copy()
    half[:, half.shape[1] // 2:] = False
    other = CoverageArea(area.omap, half)
    medium = _medium(0.0)
    room = area.mask.size * BYTES_PER_CELL * 3 // 2  # one union at a time
    heard = HeardCells(medium.hearing, medium.kernels, cache_bytes=room)
    for k in range(4):
        for a in (area, other, area):
            xy = pool[k:k + 8]
            np.testing.assert_array_equal(heard.covered(a, xy, medium.reach), _afresh(medium, a, xy))
            kept = [(memo.area, u) for memo in heard.areas.values() for u in memo.unions]
            assert [kept_area for kept_area, _ in kept] == [a]  # the other area's union made room
            assert sum(u.nbytes for _, u in kept) <= room


def _blocks_with_cells_left(area: CoverageArea, union: np.ndarray) -> np.ndarray:
    """Per block of :data:`BLOCK` cells a side: whether it holds a mask cell the union does not cover."""
    rows, cols = area.mask.shape
    left = np.zeros((-(-rows // BLOCK) * BLOCK, -(-cols // BLOCK) * BLOCK), dtype=bool)
    left[:rows, :cols] = area.mask & ~union
    return left.reshape(left.shape[0] // BLOCK, BLOCK, left.shape[1] // BLOCK, BLOCK).any(axis=(1, 3))


def test_a_block_with_no_cell_left_to_decide_is_not_looked_at_again():
    area, pool = _world()
    medium = _medium(4.0)
    heard = HeardCells(medium.hearing, medium.kernels)
    routers = pool[:12]
    heard.covered(area, routers, medium.reach)
    union = next(iter(heard.areas.values())).unions[0]
    skipped = union.blocks == 0
    assert skipped.sum() > 300  # blocks the routers cover whole, or that hold no mask cell
    assert not (skipped & _blocks_with_cells_left(area, union.union)).any()  # never one with a cell left
    # the kernel looks at no cell of a block marked so: with every block marked, a node marks nothing
    args = (NO_KEYS, area.mask, medium.heard.cells(area.omap), float(medium.reach))
    out = np.zeros(area.mask.shape, dtype=bool)
    rest = (NO_OWNER, full_window(out.shape), medium.hearing.plain())
    assert medium.kernels.heard_cells(pool[12:], *args, out, *rest, np.zeros_like(union.blocks)) == 0
    assert medium.kernels.heard_cells(pool[12:], *args, out, *rest, block_grid(out.shape)) > 0
    # a router that leaves opens the blocks of the cells it marked first again: the union stays exact
    for xy in (routers[1:], routers[2:], pool[:3]):
        np.testing.assert_array_equal(heard.covered(area, xy, medium.reach), _afresh(medium, area, xy))
        assert not ((union.blocks == 0) & _blocks_with_cells_left(area, union.union)).any()


def test_blocks_holding_marks_the_blocks_of_the_true_cells():
    rng = np.random.default_rng(3)
    for i0, j0, rows, cols in [(0, 0, 16, 24), (5, 3, 37, 50), (13, 7, 1, 1), (9, 62, 20, 70)]:
        cells = rng.random((rows, cols)) < 0.01
        want = np.zeros(((i0 + rows - 1) // BLOCK - i0 // BLOCK + 1, (j0 + cols - 1) // BLOCK - j0 // BLOCK + 1),
                        np.uint8)
        for i, j in zip(*np.nonzero(cells), strict=True):
            want[(i0 + i) // BLOCK - i0 // BLOCK, (j0 + j) // BLOCK - j0 // BLOCK] = 1
        assert np.array_equal(_blocks_holding(cells, i0, j0), want)
