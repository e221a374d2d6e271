"""The identity of a run: the fully resolved scenario as canonical JSON, and its hash.

Two runs are the same run when their resolved scenarios and seeds are equal. *Resolved* means: the validated
:class:`~amronet.scenario.Scenario` dumped to plain data, with the algorithm's parameters replaced by the
algorithm's own validated parameter model (so defaults are spelt out: ``{}`` and ``{triangular: local}`` are
the same run for self-spreading), and a map given as a file path made absolute (so the same relative path seen
from two folders is not taken for one map, and a worker on another machine of a shared file system finds it).
*Canonical JSON* sorts keys and drops whitespace; the hash is its SHA-256.

Example:
    >>> from amronet.scenario import load_scenario
    >>> a = resolve_scenario(load_scenario("self-spreading-6x6"))
    >>> b = resolve_scenario(load_scenario("self-spreading-6x6", {"algorithm.params": {}}))
    >>> scenario_hash(a) == scenario_hash(b)
    True
"""

from __future__ import annotations

import hashlib
import json
from pathlib import Path
from typing import Any

from amronet.scenario import Scenario

__all__ = ["canonical_json", "resolve_scenario", "scenario_hash"]


def canonical_json(data: Any) -> str:
    """Plain data as canonical JSON: keys sorted, no whitespace, UTF-8 kept as is."""
    return json.dumps(data, sort_keys=True, separators=(",", ":"), ensure_ascii=False, allow_nan=False)


def _resolved_map(scenario: Scenario) -> str:
    from amronet.world.builtin import BUILTIN_MAPS

    ref = scenario.map
    if ref in BUILTIN_MAPS:
        return ref
    path = Path(ref)
    looks_like_path = ref.endswith((".yaml", ".yml")) or "/" in ref
    if looks_like_path and scenario.base_dir and not path.is_absolute():
        path = Path(scenario.base_dir) / path
    return str(path.resolve())


def resolve_scenario(scenario: Scenario) -> dict[str, Any]:
    """The scenario as fully resolved plain data (see the module docstring); loading it gives the same run.

    Args:
        scenario: A validated scenario.

    Returns:
        A JSON-compatible dict.
    """
    data = scenario.to_dict()
    data["algorithm"]["params"] = scenario.algorithm_params().model_dump(mode="json")
    data["map"] = _resolved_map(scenario)
    return data


def scenario_hash(resolved: dict[str, Any]) -> str:
    """SHA-256 (hex) of a resolved scenario's canonical JSON."""
    return hashlib.sha256(canonical_json(resolved).encode()).hexdigest()
