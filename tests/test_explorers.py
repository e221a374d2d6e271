"""The explorer registry: what is registered, unknown names, and a package that imports without a cycle."""

import ast
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import amronet.algorithms.explorers as explorers_pkg
from amronet.algorithms.explorers import EXPLORERS, Explorer, FrontierExplorer, RandomExplorer
from amronet.errors import ScenarioError
from amronet.registry import Registry

PACKAGE = Path(explorers_pkg.__file__).parent


def test_the_registry_holds_the_random_the_frontier_and_the_wall_following_explorer():
    assert isinstance(EXPLORERS, Registry)
    assert list(EXPLORERS) == ["random", "frontier", "wall-follow"]
    assert EXPLORERS["random"] is RandomExplorer and EXPLORERS["frontier"] is FrontierExplorer
    assert RandomExplorer.name == "random" and FrontierExplorer.name == "frontier"
    assert all(issubclass(cls, Explorer) for cls in EXPLORERS.values())


def test_an_unknown_explorer_is_one_line_naming_the_field_and_the_choices():
    with pytest.raises(ScenarioError) as err:
        EXPLORERS.lookup("telepathy", "algorithm.params.explorer")
    assert "algorithm.params.explorer" in str(err.value) and "frontier, random, wall-follow" in str(err.value)


def test_the_random_explorer_turns_after_a_refused_move():
    ex = RandomExplorer(0.5, 0.6, 0.25, 2.0, (0.0, 8.0, 0.0, 8.0))
    heading = np.zeros(3)
    ex.steer(heading, np.array([1, 2]), np.full((2, 16), 2.0), 2.0, np.array([True, False]),
             np.random.default_rng(0), np.zeros((3, 2)), np.zeros((1, 2)))
    assert heading[0] == 0.0 and heading[1] != 0.0


@pytest.mark.parametrize("module", ["amronet.algorithms.explorers.frontier.explorer",
                                    "amronet.algorithms.explorers.random_walk", "amronet.algorithms.agent_assisted"])
def test_any_module_imports_first_and_registers_every_explorer(module):
    code = f"import {module}; from amronet.algorithms.explorers import EXPLORERS; print(sorted(EXPLORERS))"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.strip() == "['frontier', 'random', 'wall-follow']"


def test_modules_of_the_explorers_import_no_private_names():
    for path in sorted(PACKAGE.rglob("*.py")):
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.ImportFrom):
                private = [a.name for a in node.names if a.name.startswith("_")]
                assert not private, f"{path.relative_to(PACKAGE)} imports {private} from {node.module}"


def test_wall_follow_sweeps_the_office_floor_that_the_random_walk_does_not():
    """Issue #15: agents that follow walls leave their start rooms; every agent stays connected (tethered rule)."""
    import amronet
    from amronet.experiments.common import agent_scenario

    def coverage(explorer: str) -> dict:
        sc = agent_scenario("office-32x32", 6.0, ((1.0, 1.0),), 3, explorer, 900.0)
        return amronet.run(amronet.load_scenario(sc), seed=2).summary

    walls, random = coverage("wall-follow"), coverage("random")
    assert walls["coverage"] > random["coverage"] + 0.2
    assert walls["agents_connected_min"] == 1.0 and walls["routers_connected_fraction"] == 1.0
