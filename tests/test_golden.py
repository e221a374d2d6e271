"""Outputs for fixed scenarios and seeds stay bit for bit what they were (fingerprints in ``golden/outputs.json``).

The fingerprints were taken before the engine was restructured; a refactoring must not change any of them. A
change meant to change results regenerates them (see ``golden_cases.py``) and says so in its commit.
"""

import json
from pathlib import Path

import pytest

import golden_cases

GOLDEN = json.loads((Path(__file__).parent / "golden" / "outputs.json").read_text())


@pytest.mark.parametrize("name", sorted(golden_cases.RUNS))
def test_single_runs_are_unchanged(name):
    assert golden_cases.run_case(name) == GOLDEN["runs"][name]


@pytest.mark.parametrize("name", sorted(golden_cases.BATCHES))
def test_batched_runs_are_unchanged(name):
    assert golden_cases.batch_case(name) == GOLDEN["batches"][name]


@pytest.mark.parametrize("name", golden_cases.FIGURES)
def test_quick_figures_are_unchanged(name):
    assert golden_cases.figure_case(name) == GOLDEN["figures"][name]
