"""Local search: re-solve one window of the placement at a time, the rest fixed, for fewer routers.

A window is the ``window`` kept sites nearest a chosen router; the sites outside it keep their choice and HiGHS
looks, within ``node_limit`` branch-and-bound nodes, for a placement with at least one router fewer (the same
integer program, a few dozen free sites: a fraction of a second each). Windows go round the chosen routers in
turn; a pass that improves nothing, or the time budget, ends the search. A large neighbourhood search in the sense of
Shaw (1998); with a node limit, not a time limit, on each window, the result does not depend on the machine's speed
unless the budget runs out.

P. Shaw, Using constraint programming and local search methods to solve vehicle routing problems, CP 1998.
"""

from __future__ import annotations

import time

import numpy as np

from amronet.optimum.model import solve

__all__ = ["improve"]

WINDOW_NODES = 400
"""Branch-and-bound nodes a window's search may take."""


def improve(model: tuple, xy: np.ndarray, chosen: np.ndarray, budget: float, window: int = 40,
            passes: int = 3) -> tuple[np.ndarray, int]:
    """Improve a covering, connected placement window by window (see the module docstring).

    Args:
        model: The integer program over the kept sites (:func:`~amronet.optimum.model.flow_model`).
        xy: Positions of the kept sites ``(k, 2)``.
        chosen: The placement, a mask over the kept sites.
        budget: Seconds at most.
        window: Free sites per window.
        passes: Rounds over the chosen routers at most.

    Returns:
        ``(placement, windows solved)``; the placement is never worse than ``chosen``.
    """
    k = len(xy)
    best = chosen.copy()
    if k <= window:  # one window would be the whole problem: the solver's, next
        return best, 0
    t_end = time.perf_counter() + budget
    solved = 0
    for _ in range(passes):
        improved = False
        for centre in np.flatnonzero(best).tolist():
            left = t_end - time.perf_counter()
            if left <= 0:
                return best, solved
            if not best[centre]:
                continue
            d = np.hypot(xy[:, 0] - xy[centre, 0], xy[:, 1] - xy[centre, 1])
            free = np.argsort(d, kind="stable")[:window]
            fixed = best.astype(np.int64)
            fixed[free] = -1
            res = solve(model, k, left, cutoff=int(best.sum()) - 1, fixed=fixed, node_limit=WINDOW_NODES)
            solved += 1
            if res.chosen is not None and res.value is not None and res.value < best.sum():
                best = res.chosen
                improved = True
        if not improved:
            break
    return best, solved
