"""Tests of amronet.patterns, its figure (amronet.viz.patterns) and its subcommand (amronet.cli.patterns)."""

from __future__ import annotations

import argparse
import json
import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from PIL import Image

from amronet.cli.patterns import add_parser
from amronet.errors import AmronetError
from amronet.patterns import (
    DENSITY,
    PATTERNS,
    as_area,
    estimate,
    is_connected,
    lattice,
    pattern_links,
    place,
    place_all,
)
from amronet.viz.patterns import save_patterns_figure
from amronet.world import OCCUPIED, OccupancyMap, reachable_free

H_STRIP = 1 + math.sqrt(3) / 2  # r-strip row spacing / r


@pytest.fixture(scope="module")
def open_32() -> dict[float, dict]:
    """All four patterns placed in 32 m x 32 m for r = 4 .. 10 (shared: placing is the slow part)."""
    return {float(r): place_all((32.0, 32.0), float(r)) for r in range(4, 11)}


# -- the infinite patterns ---------------------------------------------------------------------------------


@pytest.mark.parametrize("pattern", PATTERNS)
def test_density_of_the_infinite_pattern(pattern):
    r, side = 1.5, 300.0  # 200 r x 200 r: edge effects ~1 %
    xy, _ = lattice(pattern, r, side, side, offset=(0.3, 0.7))
    assert len(np.unique(xy.round(9), axis=0)) == len(xy)
    assert len(xy) / side**2 * r**2 == pytest.approx(DENSITY[pattern], rel=0.02)


@pytest.mark.parametrize("pattern", PATTERNS)
def test_lattice_links_are_exactly_r_and_connected(pattern):
    r = 2.0
    xy, _ = lattice(pattern, r, 30.0, 24.0)
    assert is_connected(xy, r)
    links = pattern_links(xy, r)
    length = np.hypot(*(xy[links[:, 0]] - xy[links[:, 1]]).T)
    expected = np.sqrt((r / 4) ** 2 + (H_STRIP * r / 2) ** 2)  # connector to row node
    assert np.all(np.isclose(length, r) | np.isclose(length, expected))


def test_estimates_match_the_paper():
    assert estimate("r-strip", 32 * 32, 4) == 35
    assert estimate("hexagonal", 32 * 32, 4) == 50
    assert estimate("square", 32 * 32, 4) == 64  # exact products are not rounded up
    assert estimate("triangular", 100, 10) == 2
    with pytest.raises(ValueError, match="pattern"):
        estimate("pentagonal", 100, 1)
    with pytest.raises(ValueError, match="r must"):
        estimate("square", 100, 0)


# -- placements on the open 32 m x 32 m field --------------------------------------------------------------


def test_paper_example_r4(open_32):
    res = open_32[4.0]
    assert (res["r-strip"].estimate, res["r-strip"].count) == (35, 44)  # the paper: 35 / 44
    assert (res["hexagonal"].estimate, res["hexagonal"].count) == (50, 55)  # the paper: 50 / 55
    # the paper's Fig. 6: these minimum placements still leave (tiny) holes at the edges
    assert 0.9998 < res["r-strip"].coverage < 1.0
    assert 0.9998 < res["hexagonal"].coverage < 1.0


def test_strict_full_coverage_needs_more_nodes():
    strict = place("r-strip", (32.0, 32.0), 4.0, tol=0.0)
    assert strict.count == 46 and strict.raster_coverage == 1.0  # rows of 9 and 8 nodes plus 4 connectors
    assert strict.coverage > 0.99999


@pytest.mark.parametrize("r", [4.0, 5.0, 6.0, 7.0, 8.0, 9.0, 10.0])
def test_placements_on_open_rectangle(open_32, r):
    for name, p in open_32[r].items():
        assert p.pattern == name and p.count == len(p.xy) == len(p.connector)
        assert p.connected and is_connected(p.xy, r)
        assert np.all((p.xy >= -1e-9) & (p.xy <= 32 + 1e-9)), name
        assert p.coverage > 0.99, name
        assert p.count >= math.ceil(32 * 32 / (math.pi * r * r))  # no placement beats disk-area packing
        if name in ("r-strip", "hexagonal"):  # tight coverings: a bounded area needs at least the estimate
            assert p.count >= p.estimate, name
        assert p.count == len(np.unique(p.xy.round(9), axis=0))


def test_placement_is_the_lattice_at_its_offset(open_32):
    for p in open_32[5.0].values():
        xy, conn = lattice(p.pattern, 5.0, 32.0, 32.0, offset=p.offset, rotated=p.rotated)
        assert len(xy) == p.count and conn.sum() == p.connector.sum()
        d = np.hypot(*(xy[:, None, :] - p.xy[None, :, :]).transpose(2, 0, 1))
        assert d.min(axis=1).max() < 1e-6


def test_rstrip_connectors_join_adjacent_rows(open_32):
    for r in (4.0, 7.0, 10.0):
        p = open_32[r]["r-strip"]
        rows, conn = p.xy[~p.connector], p.xy[p.connector]
        axis = 0 if p.rotated else 1  # the coordinate across the rows
        levels = np.unique(rows[:, axis].round(6))
        assert len(conn) == len(levels) - 1  # one connector per pair of adjacent rows
        assert np.allclose(np.diff(levels), H_STRIP * r)
        for c in conn:
            d = np.hypot(*(rows - c).T)
            across = rows[:, axis] - c[axis]
            assert d[across > 0].min() <= r and d[across < 0].min() <= r  # within r of both rows
            assert np.isclose(d.min(), math.sqrt(1 / 16 + H_STRIP**2 / 4) * r)


def test_search_options_and_bad_input():
    p = place("triangular", (20.0, 12.0), 3.0, rotations=False, steps=4)
    assert not p.rotated and p.connected
    assert place("square", (30.5, 20.0), 4.0).connected
    for bad in (dict(r=-1.0), dict(r=float("nan")), dict(steps=0), dict(tol=1.0)):
        kw = dict(r=4.0) | bad
        with pytest.raises(ValueError):
            place("square", (32.0, 32.0), **kw)
    with pytest.raises(ValueError, match="rectangle"):
        place("square", (0.0, 32.0), 4.0)
    with pytest.raises(ValueError, match="common divisor"):
        place("square", (math.pi, 3.0), 1.0)
    with pytest.raises(ValueError, match="pattern"):
        place("octagonal", (32.0, 32.0), 4.0)


# -- placements on masks -----------------------------------------------------------------------------------


def _walled_map() -> OccupancyMap:
    """20 m x 16 m at 0.1 m/cell with a 0.5 m thick wall across x = 9.75 .. 10.25, a 2 m door at the top."""
    cells = np.zeros((160, 200), dtype=np.int8)
    cells[:140, 97:103] = OCCUPIED
    return OccupancyMap("walled", 0.1, (0.0, 0.0), cells)


def test_masked_map_with_a_wall():
    omap = _walled_map()
    mask = reachable_free(omap, np.array([1.0, 1.0]))
    res = place_all((omap, mask), 3.0)
    for name, p in res.items():
        rows, cols = omap.world_to_cell(p.xy)
        assert np.all(mask[rows, cols]), name  # every node in a counted cell ...
        assert not np.any(omap.cells[rows, cols] == OCCUPIED), name  # ... never in the wall
        assert p.connected and p.coverage > 0.99, name
        assert p.estimate == estimate(name, as_area((omap, mask)).area_m2, 3.0)


def test_disconnected_mask_is_reported_not_raised():
    cells = np.full((100, 300), OCCUPIED, dtype=np.int8)
    cells[:, :100] = 0  # two free rooms, 10 m apart
    cells[:, 200:] = 0
    omap = OccupancyMap("two-rooms", 0.1, (0.0, 0.0), cells)
    p = place("square", omap, 2.0)  # the mask defaults to the free cells
    assert not p.connected and p.count > 0
    assert np.all(omap.is_free(p.xy))


# -- figure and command line -------------------------------------------------------------------------------


def test_figure_png_and_svg(open_32, tmp_path):
    png = save_patterns_figure(open_32[4.0], (32.0, 32.0), 4.0, tmp_path / "p.png", dpi=50)
    img = np.asarray(Image.open(png).convert("RGB"))
    assert img.shape[0] > 200 and img.shape[1] > 200
    assert (img < 250).any(axis=2).mean() > 0.2  # not blank: disks, nodes, links drawn
    assert len(np.unique(img.reshape(-1, 3), axis=0)) > 20
    svg = save_patterns_figure(list(open_32[8.0].values())[:2], (32.0, 32.0), 8.0, tmp_path / "p.svg")
    text = svg.read_text()
    assert text.count("r-strip: ") == 1 and "hexagonal: " in text
    again = save_patterns_figure(list(open_32[8.0].values())[:2], (32.0, 32.0), 8.0, tmp_path / "q.svg")
    assert again.read_bytes() == svg.read_bytes()  # no random clip-path ids, no date
    with pytest.raises(ValueError, match="png"):
        save_patterns_figure(open_32[4.0], (32.0, 32.0), 4.0, tmp_path / "p.jpg")


def _parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog="amronet")
    add_parser(p.add_subparsers(dest="command", required=True))
    return p


def _run(*argv: str) -> int:
    args = _parser().parse_args(["patterns", *argv])
    return args.func(args)


def test_cli_prints_the_table(capsys, tmp_path):
    out = tmp_path / "fig.png"
    assert _run("--area", "32x32", "--r", "4", "--out", str(out)) == 0
    lines = capsys.readouterr().out.splitlines()
    assert lines[1].split() == ["pattern", "density", "estimated", "placed", "coverage", "%", "connected"]
    table = {line.split()[0]: line.split()[1:] for line in lines[2:6]}
    assert table["r-strip"][:3] == ["0.536", "35", "44"] and table["hexagonal"][:3] == ["0.770", "50", "55"]
    assert all(row[-1] == "yes" for row in table.values())
    assert out.is_file() and out.stat().st_size > 10_000


def test_cli_json_and_map(capsys):
    assert _run("--r", "6", "--map", "office-32x32", "--base", "1,1", "--json") == 0
    doc = json.loads(capsys.readouterr().out)
    assert [p["pattern"] for p in doc["patterns"]] == list(PATTERNS)
    assert all(p["connected"] and len(p["xy"]) == p["placed"] for p in doc["patterns"])


@pytest.mark.parametrize(
    ("argv", "option"),
    [
        (["--area", "32", "--r", "4"], "--area"),
        (["--area", "32xfoo", "--r", "4"], "--area"),
        (["--area", "0x32", "--r", "4"], "--area"),
        (["--area", "32x32", "--r", "four"], "--r"),
        (["--area", "32x32", "--r", "0"], "--r"),
        (["--area", "32x32", "--r", "inf"], "--r"),
        (["--r", "4", "--out", "fig.jpg"], "--out"),
        (["--r", "4", "--base", "1,1"], "--base"),
        (["--r", "4", "--map", "office-32x32", "--base", "1"], "--base"),
        (["--r", "4", "--map", "office-32x32", "--base", "40,3"], "--base"),
        (["--r", "4", "--map", "office-32x32", "--area", "32x32"], "--area"),
    ],
)
def test_cli_errors_are_one_line(argv, option):
    with pytest.raises(AmronetError) as info:
        _run(*argv)
    message = str(info.value)
    assert message.startswith(option) and "\n" not in message


def _strip_connectors_by_dictionary(p, u, j, ok):
    """The r-strip's connectors as first written, with a dictionary and a Python union-find (the reference)."""
    n = len(p)
    index = {(int(a), int(b)): k for k, (a, b) in enumerate(zip(u, j, strict=True))}
    parent = list(range(n))

    def find(a):
        while parent[a] != a:
            parent[a] = parent[parent[a]]
            a = parent[a]
        return a

    for (a, b), k in index.items():
        q = index.get((a + 2, b))
        if q is not None:
            parent[find(q)] = find(k)
    cand = sorted((b, 2 * a + du, k, q) for (a, b), k in index.items() for du in (-1, 1)
                  if (q := index.get((a + du, b + 1))) is not None)
    if not cand:
        return np.empty((0, 2))
    ks = np.array([c[2] for c in cand])
    qs = np.array([c[3] for c in cand])
    mids = (p[ks] + p[qs]) / 2
    good = ok(mids)
    out = []
    for m, k, q in zip(range(len(cand)), ks, qs, strict=True):
        if good[m]:
            a, b = find(int(k)), find(int(q))
            if a != b:
                parent[b] = a
                out.append(m)
    return mids[out]


@settings(max_examples=60, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), n=st.integers(1, 60), spread=st.integers(1, 12), keep=st.floats(0.2, 1.0))
def test_strip_connectors_are_the_dictionary_versions(seed, n, spread, keep):
    # nodes on a half-step grid (some sharing a column and row: the last one stands for it), a mask of free points
    from amronet.patterns.lattices import _strip_connectors

    rng = np.random.default_rng(seed)
    j = rng.integers(-3, 3, n)
    u = 2 * rng.integers(-spread, spread, n) + j
    p = np.stack([0.5 * u + rng.random(n) * 1e-3, j * 0.9], axis=1)
    free = rng.random(4 * n) < keep

    def ok(q):
        return free[np.arange(len(q)) % len(free)]

    np.testing.assert_array_equal(_strip_connectors(p, u, j, ok), _strip_connectors_by_dictionary(p, u, j, ok))
