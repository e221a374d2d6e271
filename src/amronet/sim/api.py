"""The library's front door: load a scenario, run it with a seed, get a result."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import Any

from amronet.scenario import Scenario, load_scenario
from amronet.sim.results import RunResult
from amronet.sim.simulation import Simulation

__all__ = ["run"]


def run(
    scenario: Scenario | dict[str, Any] | str | Path,
    seed: int = 0,
    overrides: dict[str, Any] | None = None,
    progress: Callable[[float, float], None] | None = None,
) -> RunResult:
    """Run a scenario once.

    Args:
        scenario: A :class:`~amronet.scenario.Scenario`, a dict, a YAML path or a preset name.
        seed: Seed of the run's random generator; the same seed gives the same result bit for bit.
        overrides: Dotted-path fields to replace, e.g. ``{"radio.r_c": 1.5}``.
        progress: Optional callable ``(t, time_limit)`` called at every recorded step.

    Returns:
        The run's result: ``summary``, ``timeseries``, ``network``, and ``save(out_dir)``.

    Example:
        >>> import amronet
        >>> result = amronet.run("self-spreading-6x6", seed=3, overrides={"sim.time_limit": 5})
        >>> sorted(result.timeseries)[:2]
        ['components', 'connected_coverage']
    """
    sc = load_scenario(scenario, overrides)
    return Simulation(sc, seed).run(progress=progress)
