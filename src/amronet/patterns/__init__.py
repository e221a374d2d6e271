"""Static regular placement patterns for communication coverage with connectivity at ``r = r_c`` (paper 2.3, 5.1.1).

Four patterns, every link exactly ``r`` long (so each is connected in the unit-disk model):

* ``"r-strip"`` (Bai et al., MobiHoc 2006): rows ``h = (1 + sqrt(3)/2) r`` apart, nodes ``r`` apart in a row,
  odd rows shifted by ``r/2``; the rows alone cover the plane. Rows are farther apart than ``r``, so each pair
  of adjacent rows gets one *connector* at the midpoint of a row-``k`` node and its nearest row-``k+1`` node
  (``0.966 r`` from both; see ``reference/baselines.md``: the paper's printed connector coordinates are
  garbled). Density ``0.536 / r**2``.
* ``"hexagonal"``: honeycomb of edge ``r``, ``0.77 / r**2``. ``"square"``: spacing ``r``, ``1 / r**2``.
  ``"triangular"``: spacing ``r``, ``1.155 / r**2``.

:func:`estimate` is the paper's estimated count ``ceil(density * area / r**2)``; :func:`place` finds the
actual placement in a bounded area: the lattice, shifted by an offset (and optionally turned by 90 degrees),
restricted to nodes inside the area (closed rectangle, or nodes lying in a counted cell of a mask). Offsets
are searched on a grid over the lattice's fundamental cell (``steps`` divisions per side) plus the *snap*
offsets that put a node exactly on an edge of the area's bounding box (where the node count changes). The
result is the connected placement with the fewest nodes among those whose raster coverage is within ``tol``
of the highest; candidates are evaluated in order of node count, and the search stops early once one reaches
coverage ``1 - tol`` connected (no candidate with more nodes can then win).

Why a tolerance (``DEFAULT_TOL = 1e-4``, 0.01 % of the area, ~6 cells of the 256 x 256 search raster of
32 m x 32 m): near the tight coverings (r-strip, honeycomb) holes shrink continuously to nothing as the
offset approaches a snap value, so "highest coverage" below the raster's resolution is noise. With it, 32 m x
32 m at ``r = 4`` gives the paper's 44 (r-strip) and 55 (hexagonal), both leaving holes of < 0.1 m² at the
edges as the paper's Fig. 6 does; ``tol=0`` asks for the raster's full coverage: 46 and 60. The square and
triangular grids overlap so much that boundary nodes cover beyond the area: they often need *fewer* nodes
than the density estimate (64 and 72 against 64 and 74 here).

Links are tested at ``r * (1 + LINK_SLACK)``: lattice neighbours are exactly ``r`` apart, which floating-point
coordinates would otherwise break at random.

Modules: :mod:`~amronet.patterns.lattices` (the patterns, their densities and lattices),
:mod:`~amronet.patterns.area` (the area to place in), :mod:`~amronet.patterns.links` (links and connectivity)
and :mod:`~amronet.patterns.placement` (the offset search and :class:`Placement`).

Example:
    >>> estimate("r-strip", 32 * 32, 4.0), estimate("hexagonal", 32 * 32, 4.0)
    (35, 50)
    >>> p = place("r-strip", (32.0, 32.0), 4.0)
    >>> p.count, p.connected, int(p.connector.sum()), round(p.coverage, 3)
    (44, True, 4, 1.0)
"""

from amronet.patterns.area import PatternArea, as_area
from amronet.patterns.lattices import DENSITY, PATTERNS, estimate, lattice
from amronet.patterns.links import LINK_SLACK, is_connected, pattern_links
from amronet.patterns.placement import DEFAULT_STEPS, DEFAULT_TOL, Placement, place, place_all

__all__ = [
    "DEFAULT_STEPS",
    "DEFAULT_TOL",
    "DENSITY",
    "LINK_SLACK",
    "PATTERNS",
    "PatternArea",
    "Placement",
    "as_area",
    "estimate",
    "is_connected",
    "lattice",
    "pattern_links",
    "place",
    "place_all",
]
