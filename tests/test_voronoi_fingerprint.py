"""The Voronoi-cell baselines' runs stay what they were: positions and states after a fixed number of steps.

SHA-256 of the routers' positions and states after ``STEPS`` steps of each baseline at a fixed seed, on the open
field and among obstacles (where the obstacle memory cuts the cells). A change of the cells' or the rules'
arithmetic that moves any robot by one bit changes a fingerprint.

VOR's and Lloyd's were taken with the array form of the cells (NumPy and shapely) and hold for the compiled one.
Minimax's were taken again when its minimax point became the compiled smallest enclosing circle (Welzl's) instead
of the centroid of shapely's polygon of ``minimum_bounding_circle``: the two centres differ by rounding (a few
``1e-15`` m), and the runs' positions after 1 500 steps by less than ``1e-12`` m.
"""

import hashlib

import numpy as np
import pytest

from amronet.engine.robots import Role
from amronet.scenario import load_scenario
from amronet.sim import Simulation

STEPS = 160
"""Six and a half of the default rounds (25 steps each at the Bebot's speed)."""

FINGERPRINTS = {
    ("vor", "vor-obstacles-6x6", 3):
        "dd5f44d5a87674101a3f918c597184f1e2392a03f9705e3fec6d8c44d994cf41",
    ("vor", "vor-6x6", 4):
        "a3a623fba346b2c12c2ce126492f787c04fe10a1f109fe57b5d76f716297c1db",
    ("minimax", "minimax-obstacles-6x6", 3):
        "cfed4be7f77f804e7ba7665fc0d7cc45d7f70363f112ce64d0d2fc4992223b74",
    ("minimax", "minimax-6x6", 4):
        "808f7053452d4e15e2b025d4922c5b1947860ba9783e683b0c7bf0fc4c017e08",
    ("lloyd", "lloyd-obstacles-6x6", 3):
        "fca6afbecf92cfb05b878028b9d90210665d02dcd9793362d9c6e14a3513198b",
    ("lloyd", "lloyd-6x6", 4):
        "2fa96df28d05a3554c90e743d9691ce321207da8064894c04974aab917985302",
}


def fingerprint(preset: str, seed: int, steps: int = STEPS) -> str:
    """SHA-256 of the routers' positions, headings and states after ``steps`` steps of ``preset`` at ``seed``."""
    sim = Simulation(load_scenario(preset), seed)
    for _ in range(steps):
        sim.step()
    sw = sim.swarm
    routers = np.flatnonzero(sw.role == Role.ROUTER)
    digest = hashlib.sha256()
    for array in (sw.xy[routers], sw.heading[routers], sw.state[routers].astype(np.int64)):
        digest.update(np.ascontiguousarray(array).tobytes())
    return digest.hexdigest()


@pytest.mark.parametrize(("name", "preset", "seed"), sorted(FINGERPRINTS))
def test_runs_keep_their_fingerprint(name, preset, seed):
    assert fingerprint(preset, seed) == FINGERPRINTS[(name, preset, seed)]
