"""The frontier explorer's compiled kernels against their plain definitions (numpy, SciPy)."""

import ast
import inspect

import numpy as np
import pytest

from amronet.algorithms.agent_assisted.explorers.frontier import KnowledgeGrid, gap_to_uncovered, navigation
from amronet.algorithms.agent_assisted.explorers.frontier.knowledge import (
    clearance_offsets,
    paint_covered,
    paint_nodes,
    passable,
    update_passable,
)
from amronet.algorithms.agent_assisted.explorers.frontier.planning import (
    FRONTIER,
    search_buffers,
    search_target,
    update_window_counts,
    window_buffers,
)
from amronet.algorithms.agent_assisted.explorers.frontier.state import (
    AgentPlans,
    MapLayers,
    NavBuffers,
    NavSettings,
    StepInputs,
)

RES = 0.25


def traversable(score, seen, rb, off_r, off_c):
    """Every cell's :func:`passable`, by the row-wise kernel with every row flagged."""
    out = np.zeros(score.shape, dtype=bool)
    update_passable(score, seen, rb, off_r, off_c, np.ones(score.shape[0], dtype=bool), out)
    return out


def frontier_cells(score, seen):
    """Free cells with an unknown 4-neighbour (beyond the grid's edge is not unknown)."""
    unknown = np.pad(~seen, 1, constant_values=False)
    near_unknown = unknown[:-2, 1:-1] | unknown[2:, 1:-1] | unknown[1:-1, :-2] | unknown[1:-1, 2:]
    return seen & (score <= 0) & near_unknown


def random_grid(rng, rows, cols):
    score = (rng.integers(-4, 12, (rows, cols)) * (rng.random((rows, cols)) < rng.random())).astype(np.int16)
    return score, rng.random((rows, cols)) < rng.random(), rng.random((rows, cols)) < 0.5


@pytest.mark.parametrize("seed", range(6))
def test_gap_to_uncovered_equals_scipys_distance_transform(seed):
    from scipy import ndimage

    rng = np.random.default_rng(seed)
    for _ in range(40):
        rows, cols = rng.integers(1, 60, size=2)
        covered = rng.random((rows, cols)) < rng.random() ** 0.2
        yy, xx = np.mgrid[:rows, :cols]
        for _ in range(rng.integers(0, 6)):  # disks, like the nodes' coverage
            covered |= (yy - rng.uniform(0, rows)) ** 2 + (xx - rng.uniform(0, cols)) ** 2 <= rng.uniform(1, 25) ** 2
        gap = gap_to_uncovered(covered)
        if covered.all():
            assert (gap == rows + cols).all()
        else:
            assert gap.tobytes() == ndimage.distance_transform_edt(covered).tobytes()


def window_counts(marks, rows, win):
    """``counts[r, j]``: ``marks`` summed over the rows within ``win`` of ``r`` and the columns ``< j``."""
    out = np.zeros((rows, marks.shape[1] + 1), dtype=np.int64)
    for r in range(rows):
        out[r, 1:] = marks[max(0, r - win):r + win + 1].sum(0).cumsum()
    return out


@pytest.mark.parametrize("seed", range(4))
def test_window_counts_and_traversable_mask_match_their_definitions_also_when_rows_change(seed):
    rng = np.random.default_rng(seed)
    for _ in range(15):
        rows, cols = (int(v) for v in rng.integers(1, 25, size=2))
        win = int(rng.integers(0, 4))
        score, seen, covered = random_grid(rng, rows, cols)
        rb = rng.random((rows, cols)) < 0.1
        off_r, off_c = clearance_offsets(float(rng.choice([0.1, 0.3, 0.6])), RES)
        marks, counts = window_buffers((rows, cols))
        trav = np.ones((rows, cols), dtype=bool)
        changed_fr = changed_us = np.ones(rows, dtype=bool)  # first everything, then a few rows at a time
        for _ in range(4):
            update_window_counts(score, seen, covered, win, changed_fr, changed_us, marks, counts)
            update_passable(score, seen, rb, off_r, off_c, changed_fr, trav)
            frontier = frontier_cells(score, seen)
            assert (counts[0] == window_counts(frontier.astype(np.int64), rows, win)).all()
            assert (counts[1] == window_counts((seen & ~covered).astype(np.int64), rows, win)).all()
            expect = [[passable(score, seen, rb, r, c, off_r, off_c) for c in range(cols)] for r in range(rows)]
            assert (trav == np.array(expect, dtype=bool)).all()
            assert (traversable(score, seen, rb, off_r, off_c) == trav).all()
            changed_fr = rng.random(rows) < 0.2
            changed_cov = rng.random(rows) < 0.2
            new_score, new_seen, new_covered = random_grid(rng, rows, cols)
            score[changed_fr] = new_score[changed_fr]
            seen[changed_fr] = new_seen[changed_fr]
            covered[changed_cov] = new_covered[changed_cov]
            changed_us = changed_fr | changed_cov


def test_integrating_flags_exactly_the_rows_that_changed():
    rng = np.random.default_rng(3)
    grid = KnowledgeGrid((0.0, 6.0, 0.0, 5.0), RES)
    for step in range(1, 40):
        before = grid.score.copy(), grid.seen.copy()
        stamps = grid.row_stamp.copy()
        xy = rng.uniform(0.5, 4.5, size=(2, 2))
        grid.integrate(xy, rng.uniform(-np.pi, np.pi, 2), rng.uniform(0.1, 2.0, (2, 8)), 2.0, xy[:1] + 0.7)
        changed = (grid.score != before[0]).any(1) | (grid.seen != before[1]).any(1)
        assert grid.stamp == step
        assert (grid.row_stamp == np.where(changed, step, stamps)).all()


def test_painting_only_new_nodes_gives_the_same_cells():
    rng = np.random.default_rng(5)
    nodes = rng.uniform(-1.0, 9.0, size=(12, 2))
    grown = np.zeros((20, 24), dtype=bool)
    for j in range(len(nodes)):
        paint_nodes(grown, 0.0, 0.0, RES, nodes[j:j + 1], 1.3)
        whole = np.ones((20, 24), dtype=bool)
        paint_covered(whole, 0.0, 0.0, RES, nodes[:j + 1], 1.3)
        assert (grown == whole).all()


def test_the_search_leaves_its_scratch_buffers_as_it_found_them():
    rng = np.random.default_rng(11)
    for _ in range(20):
        rows, cols = (int(v) for v in rng.integers(3, 20, size=2))
        score, seen, covered = random_grid(rng, rows, cols)
        seen |= rng.random((rows, cols)) < 0.5
        trav = traversable(score, seen, np.zeros((rows, cols), bool), *clearance_offsets(0.3, RES))
        marks, counts = window_buffers((rows, cols))
        every = np.ones(rows, dtype=bool)
        update_window_counts(score, seen, covered, 2, every, every, marks, counts)
        visited = np.zeros((rows, cols), dtype=bool)
        gap = rng.random((rows, cols))
        targets = (visited, counts, gap, 2, max(0.0, gap.min()))
        claims = np.full((0, 2), -1, dtype=np.int64)
        search = search_buffers(rows * cols)
        kept = trav.copy()
        for _ in range(3):
            sr, sc = int(rng.integers(rows)), int(rng.integers(cols))
            fresh = search_target(score, seen, trav, targets, (claims, 1.0), sr, sc, 3,
                                  search_buffers(rows * cols), np.zeros(rows * cols, np.int64))
            reused = search_target(score, seen, trav, targets, (claims, 1.0), sr, sc, 3, search,
                                   np.zeros(rows * cols, np.int64))
            assert fresh == reused
            assert (search[0] == -1).all() and (trav == kept).all()



def test_a_search_with_no_cell_marked_finds_nothing_without_searching():
    # everything seen and covered: no frontier and no uncovered cell is marked, so no cell anywhere is a target; the
    # search answers at once, leaving even its scratch depths and queue as they were (a search would write them)
    rng = np.random.default_rng(5)
    for _ in range(10):
        rows, cols = (int(v) for v in rng.integers(3, 20, size=2))
        score, _, _ = random_grid(rng, rows, cols)
        seen = np.ones((rows, cols), dtype=bool)
        trav = traversable(score, seen, np.zeros((rows, cols), bool), *clearance_offsets(0.3, RES))
        marks, counts = window_buffers((rows, cols))
        every = np.ones(rows, dtype=bool)
        update_window_counts(score, seen, np.ones((rows, cols), dtype=bool), 2, every, every, marks, counts)
        assert not counts.any()
        search = search_buffers(rows * cols)
        search[1:] = -7
        before, kept, path = search.copy(), trav.copy(), np.full(rows * cols, -5, np.int64)
        sr, sc = int(rng.integers(rows)), int(rng.integers(cols))
        gap = rng.random((rows, cols))
        got = search_target(score, seen, trav, (np.zeros((rows, cols), bool), counts, gap, 2, float(gap.min())),
                            (np.full((0, 2), -1, dtype=np.int64), 1.0), sr, sc, 3, search, path)
        assert got == (0, -1, 0)
        assert (search == before).all() and (trav == kept).all() and (path == -5).all()


def test_a_search_stops_at_its_target_when_no_gap_farther_out_could_make_up_for_the_depth():
    # all covered (every cell's gap the same, as gap_to_uncovered gives it then): the nearest target wins, and the
    # search stops there instead of crossing the whole open floor to the depth of its score
    rows = cols = 40
    score = np.zeros((rows, cols), dtype=np.int16)
    seen = np.ones((rows, cols), dtype=bool)
    seen[5, 5] = False  # an unknown cell: its free neighbours are frontier cells
    trav = traversable(score, seen, np.zeros((rows, cols), bool), *clearance_offsets(0.3, RES))
    marks, counts = window_buffers((rows, cols))
    every = np.ones(rows, dtype=bool)
    update_window_counts(score, seen, np.ones((rows, cols), dtype=bool), 2, every, every, marks, counts)
    search = search_buffers(rows * cols)
    search[2] = -7
    path = np.zeros(rows * cols, np.int64)
    gap = float(rows + cols)
    targets = (np.zeros((rows, cols), bool), counts, np.full((rows, cols), gap), 2, gap)
    n, goal, kind = search_target(score, seen, trav, targets, (np.full((0, 2), -1, dtype=np.int64), 1.0), 5, 12, 3,
                                  search, path)
    assert kind == FRONTIER and goal == 5 * cols + 8 and n == 4 and path[n - 1] == goal
    assert (search[2] != -7).sum() < 200  # queued: the cells a few steps from the start, not the whole floor

def test_the_navigation_kernel_unpacks_its_named_inputs_in_the_order_of_their_fields():
    # navigate() hands the kernel its named tuples as plain tuples, which the kernel unpacks by position
    kernel = next(node for node in ast.parse(inspect.getsource(navigation)).body
                  if isinstance(node, ast.FunctionDef) and node.name == "navigate_kernel")
    unpacked = {stmt.value.id: [name.id for name in stmt.targets[0].elts] for stmt in kernel.body
                if isinstance(stmt, ast.Assign) and isinstance(stmt.targets[0], ast.Tuple)
                and isinstance(stmt.value, ast.Name)}
    assert unpacked == {"step": list(StepInputs._fields), "layers": list(MapLayers._fields),
                        "cfg": list(NavSettings._fields), "plans": list(AgentPlans._fields),
                        "work": list(NavBuffers._fields)}
