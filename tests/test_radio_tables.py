"""The path-loss media's whole tables against a straightforward computation, bit for bit, step after step.

:meth:`amronet.engine.radio.RadioMedium.update` takes shortcuts (the open radius of a node's cell, the box test, the
bit-grid walk and its early stop, the margins of pairs that stood still, the compiled drop of dead links); the
reference here takes none: every pair within reach by a double loop, its margin by the law written out (the byte
walk of :func:`~amronet.engine.walls.count_walls` for the walls, from the lower id as the medium walks), the links
those with a margin ``>= 0``. Real maps, with and without shadowing, ends anywhere in their cells and ends on and a
hair off the faces of walls; steps where 5 % of the nodes move, all move, nodes join and nodes leave.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from amronet.engine.links import keep_entries
from amronet.engine.propagation import MIN_DISTANCE_M, LinkBudget
from amronet.engine.radio import make_medium
from amronet.engine.shadowing import cell_value, link_shadowing
from amronet.engine.walls import count_walls_many, wall_grid
from amronet.world.builtin import resolve_map
from amronet.world.occupancy import OccupancyMap

MAPS = ["hospital_section", "autolab", "office-32x32", "/work/shared/maps/depot.yaml"]


def _points(omap: OccupancyMap, n: int, rng: np.random.Generator) -> np.ndarray:
    """``n`` points: two thirds anywhere in free cells, the rest on or a hair off the face of a wall cell."""
    walls, _ = wall_grid(omap)
    ox, oy, res = float(omap.origin[0]), float(omap.origin[1]), float(omap.resolution)
    r, c = np.nonzero(omap.free)
    pick = rng.choice(len(r), size=n, replace=False)
    xy = omap.cell_centres(r[pick], c[pick]) + rng.uniform(-0.5, 0.5, (n, 2)) * res
    right = np.zeros_like(omap.free)  # free cells whose right-hand neighbour is a wall cell
    right[:, :-1] = omap.free[:, :-1] & (walls[:, 1:] != 0)
    above = np.zeros_like(omap.free)  # free cells whose upper neighbour is a wall cell
    above[:-1] = omap.free[:-1] & (walls[1:] != 0)
    for k in range(n // 3):
        grid = right if k % 2 else above
        rr, cc = np.nonzero(grid)
        q = rng.integers(len(rr))
        hair = (0.0, 1e-12, 1e-9 * res, 1e-6 * res)[k % 4]  # on the face, or just inside the free cell
        along = rng.uniform(0.0, 1.0) if k % 5 else 0.0  # some on a cell corner
        if grid is right:
            xy[k] = (ox + (cc[q] + 1) * res - hair, oy + (rr[q] + along) * res)
        else:
            xy[k] = (ox + (cc[q] + along) * res, oy + (rr[q] + 1) * res - hair)
    return xy


def _reference(xy: np.ndarray, medium, omap: OccupancyMap) -> dict[str, np.ndarray]:
    """The candidates (every pair within reach) and the links of ``xy``, computed the plain way."""
    b, h, n = medium.budget, medium.hearing, len(xy)
    reach = medium.reach
    i, j = np.triu_indices(n, 1)
    dx, dy = xy[j, 0] - xy[i, 0], xy[j, 1] - xy[i, 1]
    near = dx * dx + dy * dy <= reach * reach
    i, j = i[near], j[near]
    dist = np.sqrt(dx[near] * dx[near] + dy[near] * dy[near])
    field = medium.shadowing.kernel_grid if medium.shadowing is not None else None
    m0 = []
    for a, c, d in zip(i, j, dist, strict=True):
        m = h.n10 * math.log10(h.r_c / max(float(d), MIN_DISTANCE_M))
        if field is not None:
            sa = cell_value(field.values, field.x0, field.y0, field.h, xy[a, 0], xy[a, 1])
            sb = cell_value(field.values, field.x0, field.y0, field.h, xy[c, 0], xy[c, 1])
            m += link_shadowing(sa, sb, float(d), h.corr, h.clip)
        m0.append(m)
    m0 = np.array(m0)
    walls, jump = wall_grid(omap)
    limit = np.where(m0 >= 0.0, np.floor(np.maximum(m0, 0.0) / b.wall_db) + 1, 0).astype(np.int64)
    count = count_walls_many(walls, jump, float(omap.origin[0]), float(omap.origin[1]), float(omap.resolution),
                             xy[i], xy[j], limit)
    margin = np.where(m0 >= 0.0, m0 - b.wall_db * count, m0)
    rows, cols = np.concatenate([i, j]), np.concatenate([j, i])  # both directions, rows sorted by column
    order = np.lexsort((cols, rows))
    rows, cols = rows[order], cols[order]
    dist2, margin2 = np.concatenate([dist, dist])[order], np.concatenate([margin, margin])[order]
    keep = margin2 >= 0.0
    return {"indptr": np.searchsorted(rows, np.arange(n + 1)), "indices": cols, "dist": dist2, "margin": margin2,
            "link_indptr": np.searchsorted(rows[keep], np.arange(n + 1)), "link_indices": cols[keep],
            "link_dist": dist2[keep], "link_margin": margin2[keep]}


def _assert_table(table, ref: dict[str, np.ndarray]) -> None:
    cand = table.geometric
    for name, got in (("indptr", cand.indptr), ("indices", cand.indices), ("dist", cand.dist),
                      ("margin", cand.link_margin), ("link_indptr", table.indptr), ("link_indices", table.indices),
                      ("link_dist", table.dist), ("link_margin", table.link_margin)):
        np.testing.assert_array_equal(got, ref[name], err_msg=name)
    assert (table.candidates is None) == bool((ref["margin"] >= 0.0).all())


@pytest.mark.parametrize("shadowing_db", [0.0, 5.0])
@pytest.mark.parametrize("name", MAPS)
def test_tables_equal_the_plain_computation_step_after_step(name, shadowing_db):
    """indptr, indices, dist and margins of the links and of the candidates, bit for bit, as nodes move."""
    if name.startswith("/") and not __import__("os").path.exists(name):
        pytest.skip("the shared maps are not on this machine")
    omap = resolve_map(name)
    rng = np.random.default_rng(len(name) + int(shadowing_db))
    n = 420
    free_area = np.count_nonzero(omap.free) * omap.resolution**2
    r_c = math.sqrt(12.0 * free_area / (math.pi * n)) * (0.6 if shadowing_db else 1.0)  # about 12 neighbours
    budget = LinkBudget(r_c=r_c, exponent=2.0, wall_db=6.9, shadowing_db=shadowing_db)
    medium = make_medium("multi-wall", budget, omap, rng=np.random.default_rng(3))
    xy = _points(omap, n, rng)
    cut = 0
    for step in range(6):
        if step in (1, 4):  # 5 % move (the others keep their margins)
            xy = xy.copy()
            movers = rng.choice(len(xy), size=max(1, len(xy) // 20), replace=False)
            xy[movers] += rng.uniform(-0.5, 0.5, (len(movers), 2)) * omap.resolution
        elif step == 2:  # all move
            xy = xy + rng.uniform(-0.5, 0.5, xy.shape) * omap.resolution
        elif step == 3:  # nodes join
            xy = np.vstack([xy, _points(omap, 30, rng)])
        elif step == 5:  # the last nodes leave
            xy = xy[:-45]
        ref = _reference(xy, medium, omap)
        _assert_table(medium.update(xy), ref)
        cut += int((ref["margin"] < 0.0).sum())
    assert cut > 0  # walls cut links (the dead-link drop ran)


@pytest.mark.parametrize("p", [0.0, 0.3, 0.8, 1.0])
def test_keep_entries_is_the_masked_csr(p):
    """Every pattern of kept entries, the last ones dropped or not, rows emptied: the plain masked arrays."""
    rng = np.random.default_rng(int(p * 10))
    for trial in range(40):
        n = int(rng.integers(0, 25))
        indptr = np.concatenate([[0], np.cumsum(rng.integers(0, 6, n))]).astype(np.int64)
        nnz = int(indptr[-1])
        indices = rng.integers(0, max(n, 1), nnz).astype(np.int32)
        dist, margin = rng.random(nnz), rng.normal(size=nnz)
        keep = rng.random(nnz) < p
        if trial % 3 == 1 and nnz:
            keep[-1] = False  # the last entries dropped
        out_ptr, out_idx, out_dist, out_margin = keep_entries(indptr, indices, dist, margin, keep)
        rows = np.repeat(np.arange(n), np.diff(indptr))
        np.testing.assert_array_equal(out_ptr, np.searchsorted(rows[keep], np.arange(n + 1)))
        np.testing.assert_array_equal(out_idx, indices[keep])
        np.testing.assert_array_equal(out_dist, dist[keep])
        np.testing.assert_array_equal(out_margin, margin[keep])
        assert out_ptr.dtype == np.int64 and out_idx.dtype == np.int32
