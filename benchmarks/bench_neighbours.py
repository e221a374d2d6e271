"""Benchmark the radio medium's neighbour table: amronet.engine.neighbours.neighbour_csr vs cKDTree + csr_matrix.

Points are uniform in a square sized for a density of 3.5 points per r**2 (r = 1, mean degree ~11). The
baseline is what the unit-disk medium did before: ``cKDTree(xy).query_pairs(r, output_type='ndarray')``, link
lengths, and a symmetric ``scipy.sparse.csr_matrix`` with sorted indices. Both give the same table (checked).
Times are per call on one core, after a warm-up call (numba compiles once, cached on disk).

    .venv/bin/python benchmarks/bench_neighbours.py [--sizes 3000 100000] [--seed 0]
"""

from __future__ import annotations

import argparse
import time
from collections.abc import Callable

import numpy as np
import scipy.sparse as sp
from scipy.spatial import cKDTree

from amronet.engine.neighbours import neighbour_csr

DENSITY = 3.5  # points per r**2
R = 1.0


def kdtree_csr(xy: np.ndarray, r: float) -> sp.csr_matrix:
    n = len(xy)
    pairs = cKDTree(xy).query_pairs(r, output_type="ndarray")
    length = np.linalg.norm(xy[pairs[:, 0]] - xy[pairs[:, 1]], axis=1)
    rows = np.concatenate([pairs[:, 0], pairs[:, 1]])
    cols = np.concatenate([pairs[:, 1], pairs[:, 0]])
    adj = sp.csr_matrix((np.concatenate([length, length]), (rows, cols)), shape=(n, n))
    adj.sort_indices()
    return adj


def kdtree_pairs_only(xy: np.ndarray, r: float) -> np.ndarray:
    return cKDTree(xy).query_pairs(r, output_type="ndarray")


def timeit(fn: Callable[[], object], budget: float, max_reps: int) -> tuple[float, float]:
    """Min and median seconds per call over up to ``max_reps`` calls or ``budget`` seconds."""
    times: list[float] = []
    start = time.perf_counter()
    while len(times) < max_reps and (len(times) < 5 or time.perf_counter() - start < budget):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return min(times), float(np.median(times))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sizes", type=int, nargs="+", default=[3000, 100_000])
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--budget", type=float, default=3.0, help="seconds per timed function and size")
    args = ap.parse_args()
    rng = np.random.default_rng(args.seed)

    print(f"uniform points, density {DENSITY} / r^2, r = {R}; times in ms per call (min / median)")
    cols = ("neighbour_csr", "kdtree+csr", "(query_pairs)")
    header = f"{'N':>8} {'deg':>6} " + " ".join(f"{c:>17}" for c in cols) + f" {'speed-up':>9}"
    print(header)
    print("-" * len(header))
    for n in args.sizes:
        xy = rng.uniform(0.0, np.sqrt(n / DENSITY) * R, (n, 2))
        indptr, indices, dist = neighbour_csr(xy, R)  # warm-up (and compile, the first time ever)
        ref = kdtree_csr(xy, R)
        assert np.array_equal(indptr, ref.indptr) and np.array_equal(indices, ref.indices)
        assert np.allclose(dist, ref.data, rtol=1e-15, atol=0.0)
        reps = 2000 if n <= 10_000 else 50
        ours = timeit(lambda xy=xy: neighbour_csr(xy, R), args.budget, reps)
        base = timeit(lambda xy=xy: kdtree_csr(xy, R), args.budget, reps)
        qp = timeit(lambda xy=xy: kdtree_pairs_only(xy, R), args.budget, reps)
        print(
            f"{n:>8} {len(indices) / n:>6.2f} "
            f"{ours[0] * 1e3:>8.3f} / {ours[1] * 1e3:<6.3f} "
            f"{base[0] * 1e3:>8.3f} / {base[1] * 1e3:<6.3f} "
            f"{qp[0] * 1e3:>8.3f} / {qp[1] * 1e3:<6.3f} "
            f"{base[1] / ours[1]:>8.1f}x"
        )


if __name__ == "__main__":
    main()
