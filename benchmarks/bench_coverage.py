"""Time amronet.engine.coverage: raster and exact coverage per call, and the alternative raster design.

Run: ``.venv/bin/python benchmarks/bench_coverage.py``. Prints one table; times are per call, the best of
several batches after a warm-up call (numba compiles, or loads its cache, on the warm-up).

The column ``raster/np`` is the design ``CoverageArea`` does *not* use, kept here as the measurement behind
that choice: the (row, start, end) intervals generated vectorized in numpy (with the same exact cell-centre
correction, one step each side), sorted by ``np.lexsort`` and merged and counted by a numba kernel.
"""

from __future__ import annotations

import functools
import time

import numpy as np
from numba import njit

from amronet.engine.coverage import CoverageArea
from amronet.world.occupancy import OCCUPIED, OccupancyMap


def best_time(fn, budget_s: float = 1.0, batches: int = 5) -> float:
    """Seconds per call: warm up once, size a batch to ``budget_s / batches``, return the best batch mean."""
    t0 = time.perf_counter()
    fn()
    once = max(time.perf_counter() - t0, 1e-7)
    reps = max(1, int(budget_s / batches / once))
    best = float("inf")
    for _ in range(batches if once < budget_s else 1):
        t = time.perf_counter()
        for _ in range(reps):
            fn()
        best = min(best, (time.perf_counter() - t) / reps)
    return best


@njit(cache=True)
def _merge_sorted(rows, starts, ends, prefix):
    total = 0
    n = rows.shape[0]
    k = 0
    while k < n:
        i = rows[k]
        cs = starts[k]
        ce = ends[k]
        k += 1
        while k < n and rows[k] == i:
            if starts[k] > ce:
                total += prefix[i, ce] - prefix[i, cs]
                cs = starts[k]
                ce = ends[k]
            elif ends[k] > ce:
                ce = ends[k]
            k += 1
        total += prefix[i, ce] - prefix[i, cs]
    return total


@functools.cache
def _row_prefix(area: CoverageArea) -> np.ndarray:
    """Per-row prefix sums of the mask ``(rows, cols + 1)``: the mask cells of a row's column interval."""
    prefix = np.zeros((area.mask.shape[0], area.mask.shape[1] + 1), dtype=np.int64)
    np.cumsum(area.mask, axis=1, out=prefix[:, 1:])
    return prefix


def raster_numpy_intervals(area: CoverageArea, xy: np.ndarray, r: float) -> float:
    """Raster coverage with the intervals made in numpy, then sorted and merged (see module docstring)."""
    omap = area.omap
    res, (ox, oy) = omap.resolution, omap.origin
    nrows, ncols = omap.shape
    r2 = r * r
    v = (xy[:, 1] - oy) / res - 0.5
    i0 = np.clip(np.ceil(v - r / res) - 1, 0, nrows).astype(np.int64)
    i1 = np.clip(np.floor(v + r / res) + 1, -1, nrows - 1).astype(np.int64)
    counts = np.maximum(i1 - i0 + 1, 0)
    node = np.repeat(np.arange(len(xy)), counts)
    first = np.repeat(np.cumsum(counts) - counts, counts)
    rows = i0[node] + np.arange(len(node)) - first
    x = xy[node, 0]
    dy = oy + (rows + 0.5) * res - xy[node, 1]
    dy2 = dy * dy
    hw = np.sqrt(np.maximum(r2 - dy2, 0.0))
    jlo = np.clip(np.ceil((x - hw - ox) / res - 0.5), 0, ncols).astype(np.int64)
    jhi = np.clip(np.floor((x + hw - ox) / res - 0.5) + 1, 0, ncols).astype(np.int64)

    def inside(j):
        dx = ox + (j + 0.5) * res - x
        return dx * dx + dy2 <= r2

    jlo = np.where((jlo > 0) & inside(jlo - 1), jlo - 1, jlo)
    jlo = np.where((jlo < jhi) & ~inside(jlo), jlo + 1, jlo)
    jhi = np.where((jhi < ncols) & inside(jhi), jhi + 1, jhi)
    jhi = np.where((jhi > jlo) & ~inside(jhi - 1), jhi - 1, jhi)
    keep = (dy2 <= r2) & (jlo < jhi)
    rows, jlo, jhi = rows[keep], jlo[keep], jhi[keep]
    order = np.lexsort((jlo, rows))
    return _merge_sorted(rows[order], jlo[order], jhi[order], _row_prefix(area)) / area.n_cells


def main() -> None:
    rng = np.random.default_rng(0)
    res = 0.02
    walls = np.zeros((300, 300), dtype=np.int8)
    walls[[0, -1], :] = OCCUPIED
    walls[:, [0, -1]] = OCCUPIED
    walls[100:110, 50:250] = OCCUPIED
    walls[180:250, 200:210] = OCCUPIED
    maps = {
        "open 6x6 m": OccupancyMap("open", res, (0.0, 0.0), np.zeros((300, 300), dtype=np.int8)),
        "6x6 m, walls": OccupancyMap("walls", res, (0.0, 0.0), walls),
        "open 20x20 m": OccupancyMap("big", res, (0.0, 0.0), np.zeros((1000, 1000), dtype=np.int8)),
    }
    cases = [
        ("open 6x6 m", 30, 1.0),
        ("6x6 m, walls", 30, 1.0),
        ("open 20x20 m", 3000, 1.0),
        ("open 20x20 m", 100_000, 1.0),
        ("open 20x20 m", 3000, 0.1),
        ("open 20x20 m", 100_000, 0.1),
    ]
    print(f"res = {res} m; r in metres (and cells); times per call")
    cols = ("map", "grid", "disks", "r", "raster", "raster/np", "exact", "cov.")
    widths = (-14, 9, 7, 9, 10, 10, 10, 7)
    head = " ".join(f"{c:<{-w}}" if w < 0 else f"{c:>{w}}" for c, w in zip(cols, widths, strict=True))
    print(head)
    print("-" * len(head))
    for name, n, r in cases:
        omap = maps[name]
        area = CoverageArea(omap, omap.free)
        area.polygon  # built once per map, not timed  # noqa: B018
        free = np.argwhere(omap.free)
        cells = free[rng.choice(len(free), n)]
        xy = omap.cell_centres(cells[:, 0], cells[:, 1]) + rng.uniform(-0.5, 0.5, (n, 2)) * res
        t_raster = best_time(lambda: area.fraction(xy, r))  # noqa: B023
        t_np = best_time(lambda: raster_numpy_intervals(area, xy, r), budget_s=2.0)  # noqa: B023
        assert raster_numpy_intervals(area, xy, r) == area.fraction(xy, r)
        t_exact = best_time(lambda: area.fraction(xy, r, "exact"), budget_s=2.0)  # noqa: B023
        grid = "x".join(map(str, omap.shape))
        row = (name, grid, n, f"{r:g} ({r / res:.0f})", _fmt(t_raster), _fmt(t_np), _fmt(t_exact))
        row += (f"{area.fraction(xy, r):.4f}",)
        print(" ".join(f"{c:<{-w}}" if w < 0 else f"{c:>{w}}" for c, w in zip(row, widths, strict=True)))


def _fmt(t: float) -> str:
    return f"{t * 1e6:.1f} us" if t < 1e-3 else f"{t * 1e3:.2f} ms" if t < 1.0 else f"{t:.2f} s"


if __name__ == "__main__":
    main()
