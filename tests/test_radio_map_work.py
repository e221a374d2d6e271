"""``amronet radio-map`` of many nodes: refused by its estimated work unless ``--force``, and saying how far it is."""

import numpy as np
import pytest

from amronet import limits
from amronet.cli import main
from amronet.scenario import load_scenario
from amronet.sim.assemble import build_medium
from amronet.viz.signal import SPAN_DB
from amronet.world.builtin import resolve_map

NODES = ["--node", "2.5,10", "--node", "15,5", "--node", "10,3", "--node", "5,5"]


def _lattice(name: str, count: int) -> np.ndarray:
    """``count`` free points of a 1 m lattice over the map."""
    omap = resolve_map(name)
    x0, x1, y0, y1 = omap.extent
    pts = np.array([[x, y] for x in np.arange(x0 + 0.25, x1, 1.0) for y in np.arange(y0 + 0.25, y1, 1.0)])
    return pts[omap.is_free(pts)][:count]


def _one_error_line(capsys) -> str:
    err = capsys.readouterr().err
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("amronet: error: ") and "Traceback" not in err, err
    return lines[0]


def test_a_map_over_the_work_limit_is_refused_before_any_work(tmp_path, capsys, monkeypatch):
    monkeypatch.setattr("amronet.cli.radio_map.MAX_SIGNAL_WORK", 10**5)
    out = tmp_path / "signal.png"
    assert main(["radio-map", "--map", "autolab", *NODES, "--radio", "multi-wall", "--out", str(out)]) == 2
    line = _one_error_line(capsys)
    assert line.startswith("amronet: error: --node: 4 nodes x the cells within ") and "node-cells" in line, line
    assert "give fewer --node points, or acknowledge it with --force" in line, line
    assert list(tmp_path.iterdir()) == []
    assert main(["radio-map", "--map", "autolab", *NODES, "--radio", "multi-wall", "--out", str(out), "--force",
                 "-q"]) == 0
    assert out.stat().st_size > 0


def test_the_limit_lets_hundreds_of_nodes_through_and_refuses_an_absurd_map():
    """On office-32x32 under multi-wall: 263 nodes (half a minute) are drawn, 700 need --force."""
    omap = resolve_map("office-32x32")
    sc = load_scenario({"name": "m", "map": omap.name, "base_stations": [{"x": 0.25, "y": 0.25}]},
                       {"radio.model": "multi-wall"})
    medium = build_medium(sc, omap, np.random.default_rng(0), packet_loss=False)
    reach = medium.signal_reach(-SPAN_DB)
    assert medium.heard.cells_in_reach(omap, _lattice("office-32x32", 263), reach) < limits.MAX_SIGNAL_WORK
    assert medium.heard.cells_in_reach(omap, _lattice("office-32x32", 700), reach) > limits.MAX_SIGNAL_WORK
    # one node's box is the map's cells within reach of it, clipped to the map
    assert medium.heard.cells_in_reach(omap, np.array([[16.0, 16.0]]), np.inf) == omap.cells.size
    assert medium.heard.cells_in_reach(omap, np.array([[0.0, 0.0]]), 1.0) == 21 * 21


def test_700_nodes_are_refused_at_once(tmp_path, capsys):
    args = [a for x, y in _lattice("office-32x32", 700) for a in ("--node", f"{x:g},{y:g}")]
    out = tmp_path / "signal.png"
    assert main(["radio-map", "--map", "office-32x32", "--radio", "multi-wall", *args, "--out", str(out)]) == 2
    line = _one_error_line(capsys)
    assert "--node: 700 nodes x the cells within 31.6 m of each = " in line and "--force" in line, line
    assert list(tmp_path.iterdir()) == []


def test_a_long_map_reports_its_progress_in_a_few_lines(tmp_path, capsys, monkeypatch):
    monkeypatch.setattr("amronet.cli.radio_map.PROGRESS_WORK", 0)
    args = [a for x, y in _lattice("autolab", 40) for a in ("--node", f"{x:g},{y:g}")]
    out = tmp_path / "signal.png"
    assert main(["radio-map", "--map", "autolab", "--radio", "multi-wall", *args, "--out", str(out)]) == 0
    cap = capsys.readouterr()
    lines = cap.err.strip().splitlines()
    assert [line.split(" (")[0] for line in lines] == [f"radio map: {k} of 40 nodes" for k in (10, 20, 30)], cap.err
    assert "radio map of 40 nodes on autolab" in cap.out and out.stat().st_size > 0


@pytest.mark.parametrize("radio", [{"radio.model": "multi-wall", "radio.shadowing_db": 6.0},
                                   {"radio.model": "log-distance"}, {}])
def test_progress_slices_give_the_same_map_bit_for_bit(radio):
    omap = resolve_map("autolab")
    nodes = _lattice("autolab", 37)
    sc = load_scenario({"name": "m", "map": omap.name, "base_stations": [{"x": 2.5, "y": 10.0}]}, radio)
    whole = build_medium(sc, omap, np.random.default_rng(4), packet_loss=False).signal_dbm(omap, nodes, -SPAN_DB)
    seen = []
    sliced = build_medium(sc, omap, np.random.default_rng(4), packet_loss=False).signal_dbm(
        omap, nodes, -SPAN_DB, progress=lambda done, total: seen.append((done, total)))
    np.testing.assert_array_equal(sliced, whole)
    assert seen[-1] == (37, 37) and [d for d, _ in seen] == sorted({d for d, _ in seen}) and len(seen) > 1
