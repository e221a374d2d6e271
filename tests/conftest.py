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
