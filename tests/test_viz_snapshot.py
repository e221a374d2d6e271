"""Tests of amronet.viz.snapshot: files are written, to size, and really show what was asked."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from matplotlib.figure import Figure
from mpl_toolkits.axes_grid1.anchored_artists import AnchoredSizeBar
from PIL import Image

from amronet.viz import MAP_COLOURS, Nodes, Shading, draw_map, save_map_picture, save_snapshot, snapshot_figure
from amronet.viz.decorations import nice_length
from amronet.viz.nodestyle import link_style
from amronet.world import OCCUPIED, UNKNOWN, OccupancyMap

DPI = 60


@pytest.fixture
def omap() -> OccupancyMap:
    cells = np.zeros((100, 100), dtype=np.int8)  # 5 m x 5 m at 0.05 m/cell
    cells[50:53, :60] = OCCUPIED  # a wall
    cells[90:, 90:] = UNKNOWN
    return OccupancyMap("tiny", 0.05, (0.0, 0.0), cells)


@pytest.fixture
def nodes() -> Nodes:
    xy = np.array([[0.5, 0.5], [1.5, 0.8], [2.5, 1.0], [3.5, 3.5], [1.0, 4.0], [2.0, 1.8]])
    return Nodes(
        xy=xy,
        kind=np.array(["base", "router", "router", "router", "agent", "router"]),
        state=np.array(["base", "reference", "triangle-settled", "triangle", "agent", "explore"]),
        status=np.array([0, 0, 1, 1, 0, -1]),
        links=np.array([[0, 1], [1, 2], [2, 5]]),
        r_c=0.8,
    )


def _empty_nodes(r_c: float) -> Nodes:
    s = np.array([], dtype=str)
    return Nodes(xy=np.zeros((0, 2)), kind=s, state=s, status=np.zeros(0, int), links=[], r_c=r_c)


def _read(path: Path) -> np.ndarray:
    return np.asarray(Image.open(path).convert("RGB"), dtype=np.int16)


def _pixel(fig: Figure, xy: np.ndarray) -> tuple[int, int]:
    """Image (row, col) of world point xy in the saved PNG of ``fig``."""
    fig.canvas.draw()
    px, py = fig.axes[0].transData.transform(xy)
    height = fig.get_figheight() * fig.dpi
    return int(np.rint(height - py)), int(np.rint(px))


def _light_red(img: np.ndarray) -> np.ndarray:
    target = np.array(MAP_COLOURS["uncovered"])
    return np.all(np.abs(img - target) <= 6, axis=-1)


def test_png_written_to_size_and_not_blank(tmp_path, omap, nodes):
    a = save_snapshot(tmp_path / "a.png", omap, nodes, dpi=DPI)
    b = save_snapshot(tmp_path / "b.png", omap, nodes, dpi=2 * DPI)
    img_a, img_b = _read(a), _read(b)
    fig = snapshot_figure(omap, nodes, dpi=DPI)
    w_in, h_in = fig.get_size_inches()
    assert img_a.shape[:2] == (round(h_in * DPI), round(w_in * DPI))
    assert abs(img_b.shape[0] - 2 * img_a.shape[0]) <= 1 and abs(img_b.shape[1] - 2 * img_a.shape[1]) <= 1
    assert img_a.std() > 0


def test_layout_does_not_depend_on_content(omap, nodes):
    with_nodes = snapshot_figure(omap, nodes, dpi=DPI)
    without = snapshot_figure(omap, _empty_nodes(nodes.r_c), dpi=DPI)
    assert np.allclose(with_nodes.axes[0].get_position().extents, without.axes[0].get_position().extents)


def _scale_bar(fig: Figure) -> AnchoredSizeBar:
    bars = [a for a in fig.axes[0].artists if isinstance(a, AnchoredSizeBar)]
    assert len(bars) == 1
    return bars[0]


def assert_scale_bar_outside_the_map(fig: Figure) -> None:
    """The scale bar covers neither the map nor the axis labels nor the legend, and lies inside the figure."""
    fig.canvas.draw()
    renderer = fig.canvas.get_renderer()
    ax = fig.axes[0]
    bar = _scale_bar(fig).get_window_extent(renderer)
    assert bar.width > 0 and bar.height > 0
    assert not bar.overlaps(ax.get_window_extent(renderer))  # the map's data area
    texts = [*ax.get_xticklabels(), *ax.get_yticklabels(), ax.xaxis.label, ax.yaxis.label, ax.title]
    for text in texts:
        if text.get_text():
            assert not bar.overlaps(text.get_window_extent(renderer)), text.get_text()
    assert not bar.overlaps(fig.legends[0].get_window_extent(renderer))
    assert fig.bbox.contains(bar.x0, bar.y0) and fig.bbox.contains(bar.x1, bar.y1)


@pytest.mark.parametrize("shape", [(100, 100), (40, 200), (200, 40), (10, 10)])
def test_scale_bar_is_outside_the_map(omap, nodes, shape):
    square = snapshot_figure(omap, nodes, dpi=DPI)
    assert_scale_bar_outside_the_map(square)
    # its length is to scale: a fifth of the map's width, rounded, in data units
    fig = snapshot_figure(OccupancyMap("m", 0.05, (0.0, 0.0), np.zeros(shape, np.int8)), _empty_nodes(0.5), dpi=DPI)
    assert_scale_bar_outside_the_map(fig)
    bar = _scale_bar(fig).get_window_extent(fig.canvas.get_renderer())
    (x0, _), (x1, _) = fig.axes[0].transData.transform([(0, 0), (nice_length(shape[1] * 0.05), 0)])
    assert bar.width >= x1 - x0 - 1


def test_nodes_are_drawn_where_they_are(tmp_path, omap, nodes):
    with_nodes = save_snapshot(tmp_path / "n.png", omap, nodes, dpi=DPI)
    without = save_snapshot(tmp_path / "e.png", omap, _empty_nodes(nodes.r_c), dpi=DPI)
    img_n, img_e = _read(with_nodes), _read(without)
    assert img_n.shape == img_e.shape
    fig = snapshot_figure(omap, nodes, dpi=DPI)
    for i in (0, 1, 3, 4):  # base, reference, triangle, agent
        r, c = _pixel(fig, nodes.xy[i])
        win = (slice(r - 3, r + 4), slice(c - 3, c + 4))
        assert np.abs(img_n[win] - img_e[win]).max() > 60, f"node {i} not visible"
    # far from every node and disk (top-left free area) the two pictures agree
    r, c = _pixel(fig, np.array([3.0, 4.6]))
    win = (slice(r - 2, r + 3), slice(c - 2, c + 3))
    assert np.abs(img_n[win] - img_e[win]).max() <= 2


def test_uncovered_shading(tmp_path, omap, nodes):
    reachable = omap.free.copy()
    none_covered = save_snapshot(
        tmp_path / "u.png", omap, nodes, Shading(covered=np.zeros(omap.shape, bool), reachable=reachable), dpi=DPI
    )
    all_covered = save_snapshot(
        tmp_path / "c.png", omap, nodes, Shading(covered=np.ones(omap.shape, bool), reachable=reachable), dpi=DPI
    )
    assert _light_red(_read(none_covered)).sum() > 100
    assert _light_red(_read(all_covered)).sum() == 0


def _legend(fig: Figure) -> list[str]:
    return [t.get_text() for t in fig.legends[0].get_texts()]


def test_legend_explains_covered_and_uncovered_ground(omap, nodes):
    covered_label = "covered: within $r_c$ of any\nrouter or base (moving too)"
    reachable = omap.free.copy()
    half = np.zeros(omap.shape, bool)
    half[:, :50] = True
    labels = _legend(snapshot_figure(omap, nodes, Shading(covered=half, reachable=reachable), dpi=DPI))
    assert labels.index(covered_label) + 1 == labels.index("reachable, uncovered")
    legend = snapshot_figure(omap, nodes, Shading(covered=half), dpi=DPI).legends[0]
    handle = next(h for h, t in zip(legend.legend_handles, legend.get_texts(), strict=True)
                  if t.get_text() == covered_label)
    assert tuple(handle.get_facecolor()[:3]) == (1.0, 1.0, 1.0)  # plain, like the covered ground
    all_covered = _legend(snapshot_figure(omap, nodes, Shading(covered=np.ones(omap.shape, bool)), dpi=DPI))
    assert covered_label in all_covered and "reachable, uncovered" not in all_covered
    none_covered = _legend(snapshot_figure(omap, nodes, Shading(covered=np.zeros(omap.shape, bool)), dpi=DPI))
    assert covered_label not in none_covered and "reachable, uncovered" in none_covered
    assert covered_label not in _legend(snapshot_figure(omap, nodes, dpi=DPI))  # no coverage given


def test_unreachable_shading_and_draw_map(omap):
    reachable = omap.free.copy()
    reachable[:50, :] = False  # below the wall does not count
    fig = Figure(figsize=(3, 3), dpi=DPI)
    ax = fig.add_subplot()
    im = draw_map(ax, omap, reachable=reachable)
    rgb = im.get_array()
    assert tuple(rgb[10, 10]) == MAP_COLOURS["unreachable"]  # row 10 is near the bottom
    assert tuple(rgb[70, 10]) == MAP_COLOURS["free"]
    assert tuple(rgb[51, 10]) == MAP_COLOURS["occupied"]
    assert tuple(rgb[95, 95]) == MAP_COLOURS["unknown"]
    assert ax.get_xlabel() == "x [m]" and ax.get_ylabel() == "y [m]"
    assert ax.get_xlim() == (0.0, 5.0) and ax.get_ylim() == (0.0, 5.0)


def test_svg_output(tmp_path, omap, nodes):
    path = save_snapshot(tmp_path / "s.svg", omap, nodes, dpi=DPI, title="hello svg")
    text = path.read_text()
    assert text.lstrip().startswith("<?xml") and "<svg" in text
    map_svg = save_map_picture(omap, tmp_path / "m.svg", dpi=DPI)
    assert "<svg" in map_svg.read_text()
    # byte-identical from one render to the next: no random clip-path ids, no date
    assert save_snapshot(tmp_path / "s2.svg", omap, nodes, dpi=DPI, title="hello svg").read_bytes() == \
        path.read_bytes()
    assert save_map_picture(omap, tmp_path / "m2.svg", dpi=DPI).read_bytes() == map_svg.read_bytes()
    assert "<dc:date>" not in text


def test_map_picture(tmp_path, omap):
    path = save_map_picture(omap, tmp_path / "m.png", dpi=DPI)
    img = _read(path)
    assert img.std() > 0
    assert (np.abs(img - np.array(MAP_COLOURS["occupied"])).max(axis=-1) == 0).sum() > 50


@pytest.mark.parametrize(
    ("change", "name"),
    [
        ({"xy": np.zeros((6, 3))}, "xy"),
        ({"kind": np.array(["base"] * 5)}, "kind"),
        ({"kind": np.array(["base", "router", "router", "router", "agent", "robot"])}, "kind"),
        ({"state": np.array(["base"] * 7)}, "state"),
        ({"state": np.array(["base", "reference", "triangle", "triangle", "agent", "wander"])}, "state"),
        ({"status": np.zeros((6, 1), int)}, "status"),
        ({"status": np.zeros(6)}, "status"),
        ({"links": np.array([0, 1, 2])}, "links"),
        ({"links": np.array([[0, 6]])}, "links"),
        ({"links": np.array([[0.0, 1.0]])}, "links"),
        ({"covered": np.zeros((10, 10), bool)}, "covered"),
        ({"reachable": np.zeros((100, 100), int)}, "reachable"),
        ({"r_c": 0.0}, "r_c"),
    ],
)
def test_bad_arguments_raise(tmp_path, omap, nodes, change, name):
    with pytest.raises(ValueError, match=f"^{name} "):
        shading = {k: v for k, v in change.items() if k in Shading._fields}
        drawn = nodes._replace(**{k: v for k, v in change.items() if k not in shading})
        save_snapshot(tmp_path / "x.png", omap, drawn, Shading(**shading), dpi=DPI)
    assert not (tmp_path / "x.png").exists()


def test_bad_suffix_raises(tmp_path, omap, nodes):
    with pytest.raises(ValueError, match=r"^path "):
        save_snapshot(tmp_path / "x.jpg", omap, nodes)
    with pytest.raises(ValueError, match=r"^path "):
        save_map_picture(omap, tmp_path / "x.pdf")


def test_links_thin_out_when_there_are_many(omap):
    few_width, few_colour = link_style(50)
    assert (few_width, few_colour[3]) == (0.6, 0.8)
    styles = [link_style(n) for n in (300, 1_000, 5_000, 20_000, 10**7)]
    widths, alphas = [w for w, _ in styles], [c[3] for _, c in styles]
    assert widths == sorted(widths, reverse=True) and alphas == sorted(alphas, reverse=True)
    assert widths[0] == 0.6 and widths[3] <= 0.15 + 1e-9 and alphas[3] <= 0.2 + 1e-9
    assert widths[-1] > 0 and alphas[-1] > 0  # never invisible

    # a dense swarm (3 000 nodes, ~17 000 links): the snapshot draws them thin and faint
    rng = np.random.default_rng(1)
    xy = rng.uniform(0.05, 4.95, (3000, 2))
    i, j = np.triu_indices(len(xy), 1)
    near = np.hypot(*(xy[i] - xy[j]).T) <= 0.2
    links = np.column_stack([i[near], j[near]])
    assert len(links) > 10_000
    n = len(xy)
    fig = snapshot_figure(omap, Nodes(xy=xy, kind=np.full(n, "router"), state=np.full(n, "reference"),
                                      status=np.zeros(n, int), links=links, r_c=0.2), dpi=DPI)
    coll = next(c for c in fig.axes[0].collections if c.get_zorder() == 2)
    assert coll.get_linewidth()[0] <= 0.2 and coll.get_edgecolor()[0][3] <= 0.25


def test_a_faulted_runs_snapshot_draws_without_warnings():
    import warnings

    import amronet
    from amronet.viz.run_snapshot import run_snapshot_figure

    scenario = amronet.load_scenario("self-spreading-6x6", overrides={
        "sim.time_limit": 40.0, "faults": [{"at": 30.0, "routers": 0.5}]})
    result = amronet.run(scenario, seed=2)
    assert result.summary["faults"]["nodes_failed"] > 0
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # matplotlib warned about an edge colour on the failed nodes' crosses
        fig = run_snapshot_figure(result, dpi=DPI)
        fig.canvas.draw()
    crosses = [c for c in fig.axes[0].collections if c.get_zorder() == 3.6]  # STYLE["failed"]'s z-order
    assert len(crosses) == 1 and len(crosses[0].get_offsets()) == result.summary["faults"]["nodes_failed"]
