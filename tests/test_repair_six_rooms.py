"""The failing case behind ``repair: retrace``: a six-room floor under the multi-wall radio, where ``relocate`` fails.

16 m x 12 m, six 5.3 m x 4.9 m rooms (three on each side) with 1 m doors off a 2 m corridor, 10 cm walls; one base
station in a corner room, three frontier agents dropping by the paper's rule, the multi-wall radio without
shadowing at ``r_c`` 3 m; 20 % of the deployed routers fail at 250 s, the run ends at 500 s. With seed 4 ``relocate``
leaves routers cut off to the end (they drive toward where the failed routers stood, into rooms whose walls cut the
links); ``retrace`` has every survivor back within 120 s.
"""

from __future__ import annotations

import numpy as np
import pytest

import amronet
from amronet.experiments.common import agent_scenario
from amronet.sim import Simulation
from amronet.world.occupancy import FREE, OCCUPIED, OccupancyMap

RES = 0.05


def six_rooms() -> OccupancyMap:
    """The floor above, 0.05 m cells (row 0 at y = 0)."""
    cells = np.full((240, 320), FREE, dtype=np.int8)

    def wall(x0: float, y0: float, x1: float, y1: float, what: int = OCCUPIED) -> None:
        cells[round(y0 / RES):round(y1 / RES), round(x0 / RES):round(x1 / RES)] = what

    wall(0, 0, 16, 0.1), wall(0, 11.9, 16, 12), wall(0, 0, 0.1, 12), wall(15.9, 0, 16, 12)
    wall(0, 4.9, 16, 5.0), wall(0, 7.0, 16, 7.1)  # the corridor's walls
    for x in (16 / 3, 32 / 3):
        wall(x - 0.05, 0, x + 0.05, 4.9), wall(x - 0.05, 7.1, x + 0.05, 12)
    for k in range(3):
        middle = (k + 0.5) * 16 / 3
        wall(middle - 0.5, 4.9, middle + 0.5, 5.0, FREE), wall(middle - 0.5, 7.0, middle + 0.5, 7.1, FREE)
    return OccupancyMap(name="six-rooms", resolution=RES, origin=(0.0, 0.0), cells=cells)


def six_room_run(repair: str, seed: int = 4) -> dict:
    sc = agent_scenario("open-32x32", 3.0, ((1.5, 1.5),), 3, "frontier", 500.0, radio={"model": "multi-wall"})
    sc["algorithm"]["params"]["repair"] = repair
    sc["faults"] = [{"at": 250.0, "routers": 0.2}]
    sc["sim"] = {**sc["sim"], "coverage_target": "off"}
    return Simulation(amronet.load_scenario(sc), seed=seed, omap=six_rooms()).run().summary["faults"]


@pytest.fixture(scope="module")
def six_room_faults():
    return {repair: six_room_run(repair) for repair in ("relocate", "retrace")}


def test_relocate_leaves_routers_cut_off_on_the_six_room_floor(six_room_faults):
    faults = six_room_faults["relocate"]
    assert faults["nodes_failed"] >= 3 and faults["routers_moved"] > 0
    assert faults["events"][0]["restored_after_s"] is None


def test_retrace_restores_every_survivor_there_within_120_s(six_room_faults):
    faults = six_room_faults["retrace"]
    assert faults["nodes_failed"] >= 3 and faults["routers_moved"] > 0
    assert 0 < faults["events"][0]["restored_after_s"] <= 120.0
