"""Time amronet.patterns: placing the four static patterns in 32 m x 32 m for r = 4 .. 10.

Run: ``.venv/bin/python benchmarks/bench_patterns.py [--steps N] [--tol T]``. One warm-up placement first
(numba compiles, or loads its cache); then every (pattern, r) is timed as the best of three calls, each one
a full :func:`amronet.patterns.place` on a prepared area (raster search over all offsets and both rotations,
connectivity, exact coverage of the result). The table also gives estimated / placed counts and the
exact coverage, i.e. the data of the paper's Fig. 5 static curves.
"""

from __future__ import annotations

import argparse
import time

from amronet.patterns import DEFAULT_STEPS, DEFAULT_TOL, PATTERNS, as_area, place


def best_of(fn, repeats: int = 3) -> tuple[float, object]:
    """Best wall time of ``repeats`` calls and the last result."""
    best, out = float("inf"), None
    for _ in range(repeats):
        t = time.perf_counter()
        out = fn()
        best = min(best, time.perf_counter() - t)
    return best, out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--steps", type=int, default=DEFAULT_STEPS)
    ap.add_argument("--tol", type=float, default=DEFAULT_TOL)
    args = ap.parse_args()
    place("r-strip", (32.0, 32.0), 4.0)  # warm-up
    print(f"32 m x 32 m, steps = {args.steps}, tol = {args.tol:g}; times in ms (best of 3)\n")
    print(f"{'r':>3}  " + "  ".join(f"{name:>26}" for name in PATTERNS) + f"  {'all 4':>8}")
    print(f"{'':>3}  " + "  ".join(f"{'est/placed  cov %    ms':>26}" for _ in PATTERNS))
    grand = 0.0
    for r in range(4, 11):
        area = as_area((32.0, 32.0), r=float(r))
        cells, total = [], 0.0
        for name in PATTERNS:
            dt, p = best_of(
                lambda name=name, area=area, r=r: place(name, area, float(r), steps=args.steps, tol=args.tol)
            )
            total += dt
            cells.append(f"{p.estimate:>3}/{p.count:<3} {100 * p.coverage:8.3f} {1e3 * dt:7.1f}")
        grand += total
        print(f"{r:>3}  " + "  ".join(f"{c:>26}" for c in cells) + f"  {1e3 * total:8.1f}")
    t, _ = best_of(lambda: as_area((32.0, 32.0), r=4.0))
    print(f"\npreparing the area (as_area): {1e3 * t:.1f} ms; all 28 placements: {grand:.2f} s")


if __name__ == "__main__":
    main()
