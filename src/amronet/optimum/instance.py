"""The instance: candidate sites on a lattice, the coverage sample, who covers what and who links to whom.

Everything is decided by amronet's own machinery, so that a placement the solver calls feasible is one amronet
calls covered and connected: the map, the base stations and the radio are validated as a scenario would be
(:func:`amronet.sim.assemble.build_world`, :func:`~amronet.sim.assemble.build_medium`); the area that counts is the
one a run's ``summary.json`` reports (``reachable_area_m2``: the free cells 4-connected to the base stations); a
cell is covered by a site when the radio's :meth:`~amronet.engine.radio.RadioMedium.covered_mask` says so (Eq. (1)
under the unit disk, the margin kernel under the other models), and two sites are linked when the medium's
neighbour table holds the link.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
import scipy.sparse as sp
from scipy import ndimage

from amronet.engine.coverage import CoverageArea
from amronet.engine.network import hop_counts
from amronet.engine.radio import RadioMedium
from amronet.errors import AmronetError, ScenarioError
from amronet.scenario import Scenario, load_scenario
from amronet.sim.assemble import build_medium, build_world, robot_model
from amronet.world.builtin import resolve_map
from amronet.world.occupancy import OccupancyMap
from amronet.world.space import clearance, wall_distance

__all__ = ["MAX_INCIDENCES", "MAX_SITES", "Instance", "build_instance", "check_feasible", "check_lengths",
           "instance_scenario", "scenario_option_error"]

MAX_SITES = 20_000
"""Most candidate sites an instance may have (a finer ``--spacing`` is refused: no solver proves anything there)."""

MAX_INCIDENCES = 50_000_000
"""Most (cell, site) coverage pairs an instance may hold (about 0.8 GB while it is built)."""

_CROSS = ndimage.generate_binary_structure(2, 1)

_OPTION_OF_FIELD = (("radio.r_c", "--rc"), ("radio.model", "--radio"), ("radio.wall_db", "--wall-db"),
                    ("radio.shadowing_db", "--shadowing-db"), ("radio", "--radio"), ("base_stations", "--base"),
                    ("map", "--map"))
"""Scenario fields → the option a user typed, for one-line errors."""


@dataclass(frozen=True, eq=False)
class Instance:
    """One optimum problem: pick the fewest sites so that every sample cell is covered and the sites are connected.

    Attributes:
        omap: The map.
        bases_xy: Base-station positions ``(B, 2)``; fixed nodes that count 0.
        sites: Candidate router positions ``(n, 2)``.
        lattice: Lattice coordinates ``(n, 2)`` of the sites (``site = anchor + lattice * spacing``, whole numbers);
            NaN for the few sites added off the lattice for cells no lattice site covers.
        anchor: The lattice's origin, the first base station.
        spacing: Distance between neighbouring sites (m).
        cover: CSR ``(m, n)``: ``cover[i, j]`` when site ``j`` covers sample cell ``i``.
        cells: Flat map indices ``(m,)`` of the sample cells: the reachable cells no base station covers.
        reachable: The area that counts ``(rows, cols)`` (the reachable free space).
        links: Symmetric CSR ``(n, n)`` of the links between sites.
        base_linked: ``(n,)``: the site has a link to some base station.
        medium: The radio medium (its model decides coverage and links).
        radio: The radio's description (model and link budget).
        router_radius: The routers' body radius (m): a site leaves that much room to every wall.
    """

    omap: OccupancyMap
    bases_xy: np.ndarray
    sites: np.ndarray
    lattice: np.ndarray
    anchor: tuple[float, float]
    spacing: float
    cover: sp.csr_matrix
    cells: np.ndarray
    reachable: np.ndarray
    links: sp.csr_matrix
    base_linked: np.ndarray
    medium: RadioMedium
    radio: dict[str, Any]
    router_radius: float

    @property
    def n_sites(self) -> int:
        """Number of candidate sites."""
        return len(self.sites)

    @property
    def reach(self) -> float:
        """No link and no covered cell is farther than this from its node (m)."""
        return float(self.medium.reach)

    @property
    def reachable_area_m2(self) -> float:
        """Area of the reachable free space (m²), as ``summary.json``'s ``reachable_area_m2``."""
        return float(self.reachable.sum()) * self.omap.resolution**2

    def hops(self) -> np.ndarray:
        """Fewest links from a base station to each site over all sites (1: linked to a base; ``inf``: never)."""
        n = self.n_sites
        graph = sp.bmat([[None, sp.csr_matrix(self.base_linked[None, :].astype(np.int8))],
                         [sp.csr_matrix(self.base_linked[:, None].astype(np.int8)), self.links]], format="csr")
        graph.sort_indices()
        return hop_counts(graph, np.array([0]))[1:n + 1]

    def nodes_xy(self, chosen: np.ndarray) -> np.ndarray:
        """Positions of the base stations followed by the chosen sites (indices)."""
        return np.vstack([self.bases_xy, self.sites[np.asarray(chosen, dtype=np.int64)]])


def _fail(option: str, message: str) -> AmronetError:
    return AmronetError(f"{option}: {message}")


def scenario_option_error(exc: ScenarioError) -> AmronetError:
    """A scenario's error as one line naming the ``amronet optimum`` option a user typed (``--rc``, ``--map``)."""
    option = next((o for f, o in _OPTION_OF_FIELD if exc.field == f or exc.field.startswith(f + ".")
                   or exc.field.startswith(f + "[")), None)
    return AmronetError(f"{option}: {exc.message}" if option else str(exc))


def check_lengths(r_c: float, spacing: float) -> None:
    """Refuse an ``r_c`` or a spacing that is not a finite number > 0 (one line naming ``--rc`` or ``--spacing``)."""
    if not (isinstance(spacing, int | float) and math.isfinite(spacing) and spacing > 0):
        raise _fail("--spacing", f"must be a finite number > 0 (metres), got {spacing!r}")
    if not (isinstance(r_c, int | float) and math.isfinite(r_c) and r_c > 0):
        raise _fail("--rc", f"must be a finite number > 0 (metres), got {r_c!r}")


def instance_scenario(map_name: str, bases: Sequence[tuple[float, float]], r_c: float,
                      radio: dict[str, Any] | None = None) -> Scenario:
    """The scenario an instance takes its map, base stations, routers' robot and radio from (validated as a run's).

    Raises:
        ScenarioError: A field is bad (:func:`scenario_option_error` names the option a user typed).
    """
    return load_scenario({"map": map_name, "radio": {**(radio or {}), "r_c": float(r_c)}, "routers": {"count": 0},
                          "base_stations": [{"x": float(x), "y": float(y)} for x, y in bases]})


def build_instance(map_ref: str | OccupancyMap, bases: Sequence[tuple[float, float]], r_c: float, spacing: float,
                   radio: dict[str, Any] | None = None, seed: int = 0) -> Instance:
    """Build the optimum problem of a map, its base stations and a radio on a lattice of candidate sites.

    Args:
        map_ref: A built-in map's name, a ROS map_server YAML path, or a map.
        bases: Base-station positions ``(x, y)`` in metres (at least one; each where a run accepts one).
        r_c: The radio's range ``r_c`` (m).
        spacing: Distance between neighbouring candidate sites (m); the lattice is anchored at the first base.
        radio: Radio fields beyond ``r_c`` (``model``, ``wall_db``, ``shadowing_db``, ...); ``None``: the unit disk.
        seed: Seed of the radio's random field (shadowing): the field of a run with this seed.

    Raises:
        AmronetError: Bad input (one line naming the option), or a lattice on which no placement can work.
    """
    check_lengths(r_c, spacing)
    if len(bases) == 0:
        raise _fail("--base", "give at least one base station as --base X,Y")
    radio = dict(radio or {})
    if radio.get("packet_loss"):
        raise _fail("--radio", "packet loss draws links at random each step; the optimum needs fixed links")
    try:
        omap = map_ref if isinstance(map_ref, OccupancyMap) else resolve_map(map_ref)
        scenario = instance_scenario(omap.name if isinstance(map_ref, OccupancyMap) else str(map_ref), bases, r_c,
                                     radio)
        world = build_world(scenario, omap)
        medium = build_medium(scenario, omap, np.random.default_rng(seed), packet_loss=False)
    except ScenarioError as exc:  # MapError too
        raise scenario_option_error(exc) from None
    _w, _h = omap.size_m
    if r_c < 2 * omap.resolution:
        raise _fail("--rc", f"{r_c:g} m is under two cells of map '{omap.name}' ({omap.resolution:g} m a cell): "
                            "no coverage sample can resolve it")
    if spacing < omap.resolution:
        raise _fail("--spacing", f"{spacing:g} m is finer than the map's cells ({omap.resolution:g} m); "
                                 "use at least one cell")
    router_radius = robot_model(scenario.routers.robot, "routers.robot").radius
    anchor = (float(bases[0][0]), float(bases[0][1]))
    sites, lattice = _lattice(omap, world.reachable, world.bases_xy, anchor, float(spacing), router_radius,
                              [robot_model(b.robot, "base_stations").radius for b in scenario.base_stations])
    area = CoverageArea(omap, world.reachable)
    base_cov = medium.covered_mask(area, world.bases_xy)
    cells = np.flatnonzero(world.reachable & ~base_cov)
    if len(sites) == 0 and len(cells) > 0:  # base stations that cover everything alone need no site
        raise _fail("--spacing", f"no candidate site of the {spacing:g} m lattice lies where a router fits; "
                                 "use a finer spacing")
    index = np.full(omap.shape[0] * omap.shape[1], -1, dtype=np.int64)
    index[cells] = np.arange(len(cells))
    hits = [_covered(medium, area, index, xy) for xy in sites]
    sites, lattice, hits = _repair(omap, world, medium, area, index, sites, lattice, hits, router_radius, len(cells))
    total = sum(len(h) for h in hits)
    if total > MAX_INCIDENCES:
        raise _fail("--spacing", f"{len(sites)} sites cover more than {MAX_INCIDENCES:.0e} (cell, site) pairs; "
                                 "use a coarser spacing")
    cover = _csr(np.concatenate([np.empty(0, dtype=np.int64), *hits]),
                 np.repeat(np.arange(len(sites)), [len(h) for h in hits]),
                 (len(cells), len(sites)))
    table = medium.update(np.vstack([world.bases_xy, sites]))
    nb = len(world.bases_xy)
    adj = sp.csr_matrix((np.ones(len(table.indices), dtype=np.int8), table.indices, table.indptr),
                        shape=(nb + len(sites),) * 2)
    links = adj[nb:, nb:].tocsr()
    links.sort_indices()
    base_linked = np.asarray(adj[nb:, :nb].sum(axis=1)).ravel() > 0
    inst = Instance(omap=omap, bases_xy=world.bases_xy, sites=sites, lattice=lattice, anchor=anchor,
                    spacing=float(spacing), cover=cover, cells=cells, reachable=world.reachable, links=links,
                    base_linked=base_linked, medium=medium, radio=_radio_description(scenario, medium),
                    router_radius=router_radius)
    return check_feasible(inst)


def _csr(rows: np.ndarray, cols: np.ndarray, shape: tuple[int, int]) -> sp.csr_matrix:
    m = sp.csr_matrix((np.ones(len(rows), dtype=np.int8), (rows, cols)), shape=shape)
    m.sort_indices()
    return m


def _lattice(omap: OccupancyMap, reachable: np.ndarray, bases_xy: np.ndarray, anchor: tuple[float, float],
             spacing: float, radius: float, base_radii: list[float]) -> tuple[np.ndarray, np.ndarray]:
    """The lattice points where a router stands: room for its body, reachable for it, off the base nodes' bodies.

    *Reachable for it*: the cells whose clearance leaves room for the router's body, 4-connected to the base
    stations' cells through such cells (a router drives there); the point itself is at least ``radius`` from every
    wall's square (:func:`~amronet.world.space.wall_distance`).
    """
    xmin, xmax, ymin, ymax = omap.extent
    i = np.arange(math.floor((xmin - anchor[0]) / spacing), math.ceil((xmax - anchor[0]) / spacing) + 1)
    j = np.arange(math.floor((ymin - anchor[1]) / spacing), math.ceil((ymax - anchor[1]) / spacing) + 1)
    if len(i) * len(j) > 50 * MAX_SITES:
        raise _fail("--spacing", f"{spacing:g} m puts {len(i) * len(j):,} lattice points on map '{omap.name}'; "
                                 "use a coarser spacing")
    ii, jj = np.meshgrid(i, j)
    lattice = np.stack([ii.ravel(), jj.ravel()], axis=1)
    xy = np.asarray(anchor) + lattice * spacing
    roomy = _roomy(omap, reachable, bases_xy, radius)
    ok = omap.inside(xy)
    rr, cc = omap.world_to_cell(xy[ok])
    ok[ok] = roomy[rr, cc]
    ok[ok] = wall_distance(omap, xy[ok], cap=2 * radius) >= radius
    for b, rb in zip(bases_xy, base_radii, strict=True):
        ok &= np.hypot(xy[:, 0] - b[0], xy[:, 1] - b[1]) >= radius + rb
    if ok.sum() > MAX_SITES:
        raise _fail("--spacing", f"{spacing:g} m gives {int(ok.sum()):,} candidate sites, more than {MAX_SITES:,}; "
                                 "use a coarser spacing")
    return xy[ok], lattice[ok]


def _covered(medium: RadioMedium, area: CoverageArea, index: np.ndarray, xy: np.ndarray) -> np.ndarray:
    """Sample indices of the cells a node at ``xy`` covers (the medium's own rule)."""
    hit = index[np.flatnonzero(medium.covered_mask(area, xy[None, :]))]
    return hit[hit >= 0]


MAX_REPAIRS = 1000
"""Most sites :func:`_repair` adds off the lattice."""


def _repair(omap: OccupancyMap, world: Any, medium: RadioMedium, area: CoverageArea, index: np.ndarray,
            sites: np.ndarray, lattice: np.ndarray, hits: list[np.ndarray], radius: float, m: int
            ) -> tuple[np.ndarray, np.ndarray, list[np.ndarray]]:
    """Add off-lattice sites for the sample cells no lattice site covers (a closet between lattice points).

    Each such cell gets a site at the nearest cell centre where a router fits (the region of :func:`_lattice`); its
    lattice coordinates are NaN. Cells that site does not cover either stay uncovered (refused later).
    """
    seen = np.zeros(m, dtype=bool)
    for h in hits:
        seen[h] = True
    if seen.all():
        return sites, lattice.astype(float), hits
    from scipy.spatial import cKDTree

    roomy = _roomy(omap, world.reachable, world.bases_xy, radius)
    rr, cc = np.nonzero(roomy)
    centres = omap.cell_centres(rr, cc)
    centres = centres[wall_distance(omap, centres, cap=2 * radius) >= radius]
    if len(centres) == 0:
        return sites, lattice.astype(float), hits
    tree = cKDTree(centres)
    cell_of = np.flatnonzero(index >= 0)[np.argsort(index[index >= 0])]  # sample index -> flat cell index
    extra, extra_hits, hopeless = [], [], np.zeros(m, dtype=bool)
    todo = np.flatnonzero(~seen)
    while len(todo) and len(extra) < MAX_REPAIRS:
        k = int(todo[0])
        r, c = np.unravel_index(cell_of[k], omap.shape)
        _, near = tree.query(omap.cell_centres(r, c))
        xy = centres[int(near)]
        h = _covered(medium, area, index, xy)
        seen[h] = True
        if not seen[k]:
            hopeless[k] = True
        else:
            extra.append(xy)
            extra_hits.append(h)
        todo = np.flatnonzero(~seen & ~hopeless)
    if not extra:
        return sites, lattice.astype(float), hits
    lat = np.vstack([lattice.astype(float), np.full((len(extra), 2), np.nan)])
    return np.vstack([sites, np.asarray(extra)]), lat, hits + extra_hits


def _roomy(omap: OccupancyMap, reachable: np.ndarray, bases_xy: np.ndarray, radius: float) -> np.ndarray:
    """Cells with room for a router's body, 4-connected through such cells to a base station's cell."""
    roomy = reachable & (clearance(omap) >= radius)
    labels, _ = ndimage.label(roomy, structure=_CROSS)
    r, c = omap.world_to_cell(bases_xy)
    wanted = np.zeros(labels.max() + 1, dtype=bool)
    wanted[labels[r, c]] = True  # a base's own cell may lack room for a router: then no component of it counts
    wanted[0] = False
    return wanted[labels]


def _radio_description(scenario: Any, medium: RadioMedium) -> dict[str, Any]:
    b = medium.budget
    return {"model": scenario.radio.model, "r_c": float(b.r_c), "path_loss_exponent": float(b.exponent),
            "wall_db": float(b.wall_db), "shadowing_db": float(b.shadowing_db), "reach_m": float(medium.reach)}


def check_feasible(inst: Instance) -> Instance:
    """Refuse a lattice on which no connected placement covers every sample cell (one line, naming the fix)."""
    if inst.cover.shape[0] == 0:
        return inst
    hops = inst.hops()
    usable = np.isfinite(hops)
    reached = np.asarray(inst.cover[:, usable].sum(axis=1)).ravel() > 0
    if not reached.all():
        k = int(np.flatnonzero(~reached)[0])
        x, y = inst.omap.cell_centres(*np.unravel_index(inst.cells[k], inst.omap.shape))
        lonely = "no candidate site covers" if inst.cover[k].nnz == 0 else \
            "only sites with no chain of links to a base station cover"
        raise _fail("--spacing", f"{int((~reached).sum())} reachable cells can never be covered on the "
                                 f"{inst.spacing:g} m lattice ({lonely} e.g. ({x:.2f}, {y:.2f})); use a finer "
                                 "spacing")
    return inst
