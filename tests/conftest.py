import os
from pathlib import Path

import matplotlib
import pytest

matplotlib.use("Agg")
os.environ.setdefault("MPLBACKEND", "Agg")

SHARED_MAPS = Path(__file__).resolve().parents[1].parent / "shared" / "maps"


@pytest.fixture
def shared_maps() -> Path:
    if not SHARED_MAPS.is_dir():
        pytest.skip("../shared/maps is not beside the project")
    return SHARED_MAPS


@pytest.fixture
def threaded_spreading_calls(monkeypatch) -> list:
    """Self-spreading's compiled step on its threaded path (:mod:`amronet.threads`) at any size; one entry per call.

    As in a swarm large enough for threads, no step is taken in a stretch (``SwarmStretch.applies``): every step is.
    """
    from amronet.algorithms.common import swarm_stretch
    from amronet.algorithms.self_spreading import fast as compiled_step

    calls = []
    threaded = compiled_step.sense_steer_plan_threaded

    def counting(*args):
        calls.append(1)
        return threaded(*args)

    monkeypatch.setattr(compiled_step, "use_threads", lambda n: True)
    monkeypatch.setattr(swarm_stretch, "use_threads", lambda n: True)
    monkeypatch.setattr(compiled_step, "sense_steer_plan_threaded", counting)
    return calls
