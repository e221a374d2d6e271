"""The deployment planner: how many routers must the team carry for this building?

Three answers side by side, for a map, its base stations, ``r_c`` and the agents per base station:

1. the paper's planning estimate ``0.77 A / r_c**2`` (section 5.1.1) on ``A``, the free space reachable from the
   base stations (:func:`amronet.world.reachable_free`);
2. the static patterns (r-strip, hexagonal, square, triangular) placed on that same free space
   (:func:`amronet.patterns.place_all`): what a team that could place routers anywhere would need;
3. the distribution of routers actually released by agent-assisted deployment over ``K`` seeded runs (a sweep
   through the same executors and result store as ``amronet sweep``), with the recommendation: the
   ``confidence`` quantile (default the 95th percentile) of the routers deployed in the runs that reached the
   coverage target, rounded up.

Counts: the estimate and the patterns count *nodes*; each base station has an immobile reference node that
the team does not carry, so "routers to carry" is nodes minus base stations for them, and the routers released
by the agents for agent-assisted deployment.

The parts: the planner (:mod:`~amronet.planning.planner`), its answer (:mod:`~amronet.planning.report`) and its
files (:mod:`~amronet.planning.writing`).

Example:
    >>> from amronet.experiments.options import RunOptions
    >>> p = plan("office-32x32", [(1.0, 1.0)], r_c=8.0, agents_per_base=2, runs=3, options=RunOptions(workers=1))
    >>> p.recommended >= p.distribution["median"] > 0
    True
"""

from amronet.planning.planner import PAPER_MISSION, Mission, plan
from amronet.planning.report import PLAN_ESTIMATE_DENSITY, Plan
from amronet.planning.writing import typical_picture, write_plan

__all__ = ["PAPER_MISSION", "PLAN_ESTIMATE_DENSITY", "Mission", "Plan", "plan", "typical_picture", "write_plan"]
