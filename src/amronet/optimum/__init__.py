"""The optimum: how few routers could ever cover this building, and how far a placement is from it.

**The problem.** Given a map, its base stations (fixed nodes that count 0) and a radio, choose router positions
among candidate sites so that every point of the coverage sample is covered and the routers form a network
connected to a base station, with as few routers as possible: a connected set cover (a node-weighted connected
dominating set on the bipartite graph of sites and points, rooted at the base stations).

**Candidates and sample** (:mod:`~amronet.optimum.instance`). Sites are the points of a square lattice of spacing
``s`` anchored at the first base station, where a router's body fits (its radius from every wall) and that a
router can drive to from the base stations (the cells with room for its body, 4-connected to them); a reachable
cell no lattice site covers (a closet between lattice points) gets one extra site at the nearest such point. The
coverage sample is every cell centre of the reachable free space, the area a run's ``coverage`` and
``reachable_area_m2`` count. A site covers a cell when amronet's coverage rule says so (Eq. (1) under the unit disk,
the radio's margin kernel under ``log-distance`` and ``multi-wall``), and two sites (or a site and a base station)
are linked when the radio medium's neighbour table holds the link: the same code as a run's.

**The model** (:mod:`~amronet.optimum.model`). Binary ``y_j`` per site; coverage rows ``sum_{j in S_i} y_j >= 1``;
connectivity by a single-commodity flow from the base stations in which every chosen site consumes one unit and
only chosen sites carry flow (Rebai et al. 2015); valid cuts: a chosen site not linked to a base station has a
chosen neighbour, the hop layers around the base stations are vertex separators (Buchanan et al. 2015 cut with
separators), and the chain inequality (:mod:`~amronet.optimum.bounds`). Before solving, rows covered by the same
sites merge, rows implied by a smaller row go, and dominated sites — covered rows *and* links contained in another
site's — go (:mod:`~amronet.optimum.reduce`). Solved with HiGHS through :func:`scipy.optimize.milp` under a time
limit, after a greedy connected cover, local search over windows and, on fine lattices, the lattice of twice the
spacing (:mod:`~amronet.optimum.solve`); with ``solver="cp-sat"`` OR-Tools CP-SAT, an optional extra, takes the first
half of the last phase and HiGHS goes on from its best (:mod:`~amronet.optimum.cpsat`). A result store keeps solved
problems like runs, under a hash of the problem (:mod:`~amronet.optimum.stored`).

**What is proven.** The lower bound is the largest of the solvers' proven bounds of the model, the set cover ILP's
bound (coverage alone) and the hop bounds; the gap is ``(best - bound) / bound`` and the answer is optimal when it
is 0. An optimum over a lattice of candidates is an upper bound on the optimum with routers anywhere; the lower bound
holds for the chosen coverage sample and candidate lattice only (the straight-line hop bound for any placement).

References:
    M. Rebai, M. Le Berre, H. Snoussi, F. Hnaien, L. Khoukhi, Sensor deployment optimization methods to achieve both
    coverage and connectivity in wireless sensor networks, Computers & Operations Research 59 (2015) 11-21.

    S. Elloumi, O. Hudry, E. Marie, A. Martin, A. Plateau, S. Rovedakis, Optimization of wireless sensor networks
    deployment with coverage and connectivity constraints, Annals of Operations Research 298 (2021) 183-206.

    A. Buchanan, J. S. Sung, S. Butenko, E. L. Pasiliao, An integer programming approach for fault-tolerant
    connected dominating sets, INFORMS Journal on Computing 27 (2015) 178-188.

Example:
    >>> opt = find_optimum("obstacles-6x6", [(-2.5, -2.5)], r_c=3.0, spacing=1.5, time_limit=20)
    >>> opt.count, opt.lower, opt.optimal
    (4, 4, True)
"""

from amronet.optimum.instance import Instance, build_instance
from amronet.optimum.report import CAVEAT, Optimum
from amronet.optimum.solve import find_optimum, verify
from amronet.optimum.stored import find_or_load_optimum
from amronet.optimum.writing import write_optimum

__all__ = ["CAVEAT", "Instance", "Optimum", "build_instance", "find_optimum", "find_or_load_optimum", "verify",
           "write_optimum"]
