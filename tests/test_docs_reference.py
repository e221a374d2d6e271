"""The generated reference pages (tools/docs_reference.py) hold every scenario key and every command, described."""

import sys
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tools"))
import docs_reference

from amronet.algorithms import ALGORITHMS
from amronet.cli.main import build_parser
from amronet.scenario.schema import Scenario


@pytest.fixture(scope="module")
def scenario_page():
    return docs_reference.scenario_reference()


def _rows(page):
    return [row for row in page.splitlines() if row.startswith("| `")]


def test_every_scenario_key_and_algorithm_parameter_is_in_the_reference(scenario_page):
    keys = {row.split("`")[1] for row in _rows(scenario_page)}
    for section, info in Scenario.model_fields.items():
        if not info.exclude:
            assert section in keys
    for name, cls in ALGORITHMS.items():
        assert f"## `algorithm.params` of `{name}`" in scenario_page
        for field in cls.Params.model_fields:
            assert f"algorithm.params.{field}" in keys


def test_every_key_of_the_reference_says_what_it_means(scenario_page):
    undescribed = [row.split("`")[1] for row in _rows(scenario_page) if row.rstrip().endswith("|  |")]
    assert not undescribed, f"give these fields a docstring: {undescribed}"


def test_the_cli_reference_lists_every_command():
    page = docs_reference.cli_reference()
    sub = next(a for a in build_parser()._actions if a.__class__.__name__ == "_SubParsersAction")
    for name in sub.choices:
        assert f"`amronet {name}`" in page
