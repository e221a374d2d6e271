"""``amronet reproduce walks`` (issue #15): the walk rules of self-spreading on real floor plans."""

from __future__ import annotations

import csv
import io
import math

import numpy as np

from amronet.experiments.options import RunOptions
from amronet.experiments.walks import WALK_MAPS, _first_at, run_walks, walk_scenario
from amronet.scenario import load_scenario
from amronet.world import reachable_free, resolve_map
from amronet.world.space import wall_distance


def test_every_base_station_is_a_free_point_that_reaches_most_of_its_map():
    for name, m in WALK_MAPS.items():
        omap = resolve_map(name)
        assert wall_distance(omap, np.array([m.base]))[0] >= 0.9
        assert reachable_free(omap, np.array([m.base])).sum() >= 0.6 * omap.free.sum()
        assert load_scenario(walk_scenario(name, "growth", 10.0)).algorithm_params().walk == "growth"


def test_first_time_at_a_level():
    t, v = np.array([0.0, 1.0, 2.0, 3.0]), np.array([0.1, 0.5, 0.9, 0.95])
    assert _first_at(t, v, 0.9) == 2.0 and _first_at(t, v, 0.1) == 0.0 and math.isinf(_first_at(t, v, 0.99))


def test_a_small_run_writes_rows_table_claims_and_figure(tmp_path):
    out = tmp_path / "walks"
    report = run_walks(out, maps=("cave",), walks=("growth", "random"), runs=2,
                       options=RunOptions(workers=1, show_progress=False, time_limit=30.0))
    rows = report["rows"]
    assert len(rows) == 2 * 2 and [r["walk"] for r in rows[:2]] == ["random", "random"]  # random first
    for r in rows:
        assert r["routers_connected_fraction"] == 1.0  # every deployed router has a path to the base
        assert r["time_to_90pct_s"] <= 30.0 and 0.0 < r["coverage"] <= 1.0
    assert [e["walk"] for e in report["table"]] == ["random", "growth"]
    assert len(report["claims"]) == 1 and "growth" in report["claims"][0].claim
    names = sorted(p.name for p in out.iterdir() if not p.name.startswith("."))
    assert names == ["walks.md", "walks.png", "walks_runs.csv", "walks_table.csv"]
    assert (out / "walks.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    table = list(csv.DictReader(io.StringIO((out / "walks_table.csv").read_text())))
    assert {t["walk"] for t in table} == {"random", "growth"}
