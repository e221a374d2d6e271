"""Loading a scenario: from a YAML file, a mapping, a :class:`~amronet.scenario.schema.Scenario` or a preset.

The built-in presets are the YAML files of ``amronet/data/presets``. The schema is imported only when a scenario is
validated, so a file that does not exist is refused at once; the schema itself needs the algorithms' declarations
and the radio models' traits, not their kernels (:mod:`amronet.algorithms.declaration`,
:mod:`amronet.engine.radio_traits`), so a bad scenario is refused quickly too.
"""

from __future__ import annotations

from importlib import resources
from pathlib import Path
from typing import TYPE_CHECKING, Any

from amronet.errors import MapError, ScenarioError
from amronet.scenario.overrides import apply_overrides
from amronet.world.names import unknown_map_message
from amronet.yaml_loading import load_yaml

if TYPE_CHECKING:
    from amronet.scenario.schema import Scenario

__all__ = ["list_presets", "load_scenario"]


def _preset_dir() -> Any:
    return resources.files("amronet") / "data" / "presets"


def list_presets() -> dict[str, str]:
    """Built-in scenarios: name → one-line description."""
    out = {}
    for entry in sorted(_preset_dir().iterdir(), key=lambda e: e.name):
        if entry.name.endswith(".yaml"):
            data = load_yaml(entry.read_text(), "preset", repr(entry.name))
            out[entry.name[:-5]] = str(data.get("description", ""))
    return out


def load_scenario(source: Scenario | dict[str, Any] | str | Path, overrides: dict[str, Any] | None = None) -> Scenario:
    """Load and validate a scenario.

    Args:
        source: A :class:`Scenario`, a dict, a path to a YAML file, or the name of a built-in preset
            (see :func:`list_presets`).
        overrides: Dotted-path fields to replace before validation, e.g. ``{"radio.r_c": 1.5}``.

    Returns:
        The validated scenario.

    Raises:
        ScenarioError: The source cannot be read or is invalid; the message names the field (a file naming a map
            that is neither a built-in name nor a path: a MapError).
    """
    base_dir: str | None = None
    if isinstance(source, dict):
        data = source
    elif not isinstance(source, str | Path):
        from amronet.scenario.schema import Scenario  # here, not at the top: see the module

        if not isinstance(source, Scenario):
            raise ScenarioError("scenario", f"must be a mapping of fields, a YAML path or a preset name, got "
                                            f"{type(source).__name__}")
        data, base_dir = source.given_dict(), source.base_dir
    else:
        path = Path(source)
        preset = _preset_dir() / f"{source}.yaml"
        if not path.suffix and preset.is_file():
            text, shown = preset.read_text(), f"preset {str(source)!r}"
        elif path.is_file():
            try:
                text = path.read_text()
            except (OSError, UnicodeDecodeError) as exc:
                raise ScenarioError("scenario", f"cannot read {str(path)!r}: {exc}") from None
            base_dir, shown = str(path.resolve().parent), repr(str(path))
        else:
            raise ScenarioError(
                "scenario", f"no file {str(source)!r} and no preset of that name; presets: "
                + ", ".join(list_presets())
            )
        data = load_yaml(text, "scenario", shown)
        if data is None:  # no text, or comments only
            raise ScenarioError("scenario", f"{shown} is empty; give at least map and base_stations")
    if overrides:
        data = apply_overrides(data if isinstance(data, dict) else {}, overrides)
    if isinstance(source, str | Path) and isinstance(data, dict) and isinstance(data.get("map"), str):
        # a file names a map that exists: a built-in name or a path (refused now, before any map code is imported;
        # a mapping may name a map its caller hands over as an object)
        unknown = unknown_map_message(data["map"])
        if unknown is not None:
            raise MapError("map", unknown)
    from amronet.scenario.schema import validate_scenario  # here, not at the top: see the module

    return validate_scenario(data, base_dir)
