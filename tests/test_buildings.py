"""``amronet reproduce buildings`` (issue #19): drop rules x radio x stock on real floor plans."""

from __future__ import annotations

import csv
import io

import numpy as np

from amronet.experiments.buildings import BUILDINGS, run_buildings
from amronet.experiments.options import RunOptions
from amronet.world import reachable_free, resolve_map
from amronet.world.space import wall_distance


def test_every_base_station_is_a_free_point_that_reaches_most_of_its_map():
    for b in BUILDINGS.values():
        omap = resolve_map(b.map)
        assert wall_distance(omap, np.array([b.base]))[0] >= 0.9
        reach = reachable_free(omap, np.array([b.base])).sum()
        assert reach >= 0.6 * omap.free.sum()


def test_a_small_run_writes_rows_table_claims_and_figure(tmp_path):
    out = tmp_path / "buildings"
    report = run_buildings(out, buildings=("cave",), rules=("last-reference", "link-quality"), stocks=(None, 4),
                           runs=2, options=RunOptions(workers=1, show_progress=False, time_limit=60.0,
                                                      store=str(tmp_path / "runs.sqlite")))
    rows = report["rows"]
    assert len(rows) == 2 * 2 * 2 * 2  # rules x radios x stocks x runs
    assert {r["radio"] for r in rows} == {"unit-disk", "multi-wall"}
    for r in rows:
        assert 0.0 <= r["connected_fraction"] <= 1.0
        if r["stock"] == 4:
            assert r["relays_used"] <= 4 * 3  # three agents, four routers each
        if r["rule"] == "last-reference" and r["radio"] == "unit-disk" and r["stock"] == "unlimited":
            assert r["connected_fraction"] == 1.0 and r["outages"] == 0  # the paper's world: never cut off
    assert len(report["table"]) == 8
    assert any("distance rule" in c.claim for c in report["claims"])
    names = sorted(p.name for p in out.iterdir() if not p.name.startswith("."))
    assert names == ["buildings.md", "buildings.png", "buildings_runs.csv", "buildings_table.csv"]
    assert (out / "buildings.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    table = list(csv.DictReader(io.StringIO((out / "buildings_table.csv").read_text())))
    assert {t["rule"] for t in table} == {"last-reference", "link-quality"}
    # the same runs again come from the store, unchanged
    again = run_buildings(tmp_path / "again", buildings=("cave",), rules=("last-reference", "link-quality"),
                          stocks=(None, 4), runs=2,
                          options=RunOptions(workers=1, show_progress=False, time_limit=60.0,
                                             store=str(tmp_path / "runs.sqlite")))
    strip = [{k: v for k, v in r.items() if k != "wall_time_s"} for r in rows]
    assert [{k: v for k, v in r.items() if k != "wall_time_s"} for r in again["rows"]] == strip
