"""Scenarios: one YAML file (or dict, or built-in preset) describes a whole run, validated on load.

Unknown keys, wrong types, NaN or negative radii and speeds are rejected with one line that names the field.
The parts: the schema (:mod:`~amronet.scenario.schema`), the error messages (:mod:`~amronet.scenario.messages`),
overrides (:mod:`~amronet.scenario.overrides`), loading files and presets (:mod:`~amronet.scenario.loading`), and
the defaults that follow the algorithm and the robots (:mod:`~amronet.scenario.defaults`).

Example::

    name: my-run
    map: obstacles-6x6              # a built-in map name or a path to a ROS map_server YAML
    algorithm: {name: self-spreading, params: {triangular: local}}
    radio: {model: unit-disk, r_c: 1.0}
    base_stations: [{x: 0.0, y: 0.0, region: [1.0, 1.0]}]
    routers: {count: 30, robot: bebot}
    sim: {dt: 0.1, time_limit: 300}
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

from amronet.scenario.loading import list_presets, load_scenario
from amronet.scenario.overrides import apply_overrides, parse_override

if TYPE_CHECKING:
    from amronet.scenario.messages import to_scenario_error
    from amronet.scenario.schema import (
        FAULT_KINDS,
        MAX_RANGE_M,
        AgentsSpec,
        AlgorithmSpec,
        BaseStationSpec,
        FaultSpec,
        RadioSpec,
        RobotRef,
        RobotSpec,
        RoutersSpec,
        Scenario,
        SimSpec,
        validate_scenario,
    )

_LAZY = {name: "amronet.scenario.schema" for name in (
    "FAULT_KINDS", "MAX_RANGE_M", "AgentsSpec", "AlgorithmSpec", "BaseStationSpec", "FaultSpec", "RadioSpec",
    "RobotRef", "RobotSpec", "RoutersSpec", "Scenario", "SimSpec", "validate_scenario")}
_LAZY["to_scenario_error"] = "amronet.scenario.messages"
"""Names loaded on first use: the schema (pydantic, the algorithms' declarations) is not needed to refuse a
scenario file that does not exist, nor by a command line's ``--help``. It never imports the kernels (numba, SciPy):
a bad scenario is refused without them."""

__all__ = [
    "FAULT_KINDS",
    "MAX_RANGE_M",
    "AgentsSpec",
    "AlgorithmSpec",
    "BaseStationSpec",
    "FaultSpec",
    "RadioSpec",
    "RobotRef",
    "RobotSpec",
    "RoutersSpec",
    "Scenario",
    "SimSpec",
    "apply_overrides",
    "list_presets",
    "load_scenario",
    "parse_override",
    "to_scenario_error",
    "validate_scenario",
]


def __getattr__(name: str) -> Any:
    if name not in _LAZY:
        raise AttributeError(f"module 'amronet.scenario' has no attribute {name!r}")
    value = getattr(importlib.import_module(_LAZY[name]), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted({*globals(), *_LAZY})
