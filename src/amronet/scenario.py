"""Scenarios: one YAML file (or dict, or built-in preset) describes a whole run, validated on load.

Unknown keys, wrong types, NaN or negative radii and speeds are rejected with one line that names the field.
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

import copy
import math
from importlib import resources
from pathlib import Path
from typing import Annotated, Any, Literal

from pydantic import (
    BaseModel,
    ConfigDict,
    Discriminator,
    Field,
    StrictBool,
    StrictInt,
    Tag,
    ValidationError,
    field_validator,
    model_validator,
)

from amronet.algorithms import ALGORITHMS
from amronet.engine.propagation import LinkBudget, median_range
from amronet.engine.radio import DEFAULT_WALL_DB, MEDIA
from amronet.errors import ScenarioError
from amronet.yaml_loading import load_yaml

__all__ = [
    "AgentsSpec",
    "BaseStationSpec",
    "FaultSpec",
    "RadioSpec",
    "RobotSpec",
    "RoutersSpec",
    "Scenario",
    "SimSpec",
    "apply_overrides",
    "list_presets",
    "load_scenario",
    "parse_override",
]

PositiveFloat = Annotated[float, Field(strict=True, gt=0, allow_inf_nan=False)]
NonNegativeFloat = Annotated[float, Field(strict=True, ge=0, allow_inf_nan=False)]
FiniteFloat = Annotated[float, Field(strict=True, allow_inf_nan=False)]

MAX_RANGE_M = 1e5
"""The longest median range ``radio.r_c`` (100 km): longer ones overflow the controllers' squared ranges and the
pictures' arithmetic, and no floor plan needs them."""


class _Strict(BaseModel):
    model_config = ConfigDict(extra="forbid", frozen=True)


class RobotSpec(_Strict):
    """A robot model given field by field instead of by name."""

    radius: PositiveFloat
    max_speed: NonNegativeFloat
    sensor_beams: Annotated[StrictInt, Field(ge=1, le=360)]
    sensor_range: PositiveFloat


def _robot_ref_tag(value: Any) -> str:
    return "spec" if isinstance(value, dict | RobotSpec) else "name"


RobotRef = Annotated[Annotated[str, Tag("name")] | Annotated[RobotSpec, Tag("spec")], Discriminator(_robot_ref_tag)]
"""A robot model by name (``bebot``), or field by field (a mapping: errors then name the field inside it)."""


class RadioSpec(_Strict):
    """The radio medium and its link budget (:mod:`amronet.engine.propagation`, :mod:`amronet.engine.radio`).

    Fields left out (``None``) take the model's defaults: path-loss exponent 2.5 for ``log-distance`` and the
    unit disk's RSSI, 2.0 for ``multi-wall``; shadowing 5 dB for ``log-distance``, none otherwise; 6.9 dB per
    wall (COST 231 heavy wall) for ``multi-wall``.
    """

    model: str = "unit-disk"
    r_c: PositiveFloat = 1.0
    """Median range without walls and shadowing (m): the usable threshold is derived from it."""
    tx_dbm: FiniteFloat = 20.0
    pl0_db: FiniteFloat = 40.0
    """Path loss at 1 m (dB)."""
    path_loss_exponent: PositiveFloat | None = None
    wall_db: NonNegativeFloat | None = None
    """Loss per wall crossed (dB); ``multi-wall`` only."""
    shadowing_db: NonNegativeFloat | None = None
    """Standard deviation of the spatially correlated log-normal shadowing (dB); not for the unit disk."""
    shadowing_corr_m: PositiveFloat = 2.0
    threshold_dbm: FiniteFloat | None = None
    """The usable-link threshold (dBm); given, it sets ``r_c`` (the median range it implies), so give one of the two."""
    packet_loss: StrictBool = False
    """Drop each link in each step with probability one minus its packet delivery ratio."""

    @model_validator(mode="after")
    def _check_budget(self) -> RadioSpec:
        if self.r_c > MAX_RANGE_M:
            raise ValueError(f"@radio.r_c@{self.r_c:g} m is beyond the longest range amronet models, "
                             f"{MAX_RANGE_M:g} m; give a range in metres, e.g. 1.5")
        cls = MEDIA.get(self.model)
        if cls is None:
            return self  # the scenario names the unknown model
        given = self.model_fields_set
        if not cls.uses_walls and self.wall_db is not None:
            raise ValueError(f"@radio.wall_db@the {self.model} model has no walls; use radio.model=multi-wall or "
                             "leave wall_db out")
        if not cls.uses_shadowing and (self.shadowing_db or 0.0) > 0:
            raise ValueError(f"@radio.shadowing_db@the {self.model} model has no shadowing; use radio.model="
                             "log-distance or multi-wall, or leave shadowing_db out")
        if self.threshold_dbm is not None:
            n = self.path_loss_exponent or cls.default_exponent
            implied = median_range(self.tx_dbm, self.pl0_db, n, self.threshold_dbm)
            if implied < 0.05:
                at = self.tx_dbm - self.pl0_db - 10.0 * n * math.log10(0.05)
                raise ValueError(f"@radio.threshold_dbm@{self.threshold_dbm:g} dBm is never reached: the transmitter "
                                 f"delivers {at:.1f} dBm at 5 cm; lower the threshold or raise radio.tx_dbm")
            if implied > MAX_RANGE_M:
                raise ValueError(f"@radio.threshold_dbm@{self.threshold_dbm:g} dBm puts the median range at "
                                 f"{implied:.3g} m; raise the threshold (or give radio.r_c instead)")
            if "r_c" in given and not math.isclose(implied, self.r_c, rel_tol=1e-9):
                raise ValueError(f"@radio.threshold_dbm@{self.threshold_dbm:g} dBm implies r_c = {implied:.6g} m but "
                                 f"radio.r_c is {self.r_c:g}; give only one of the two")
            object.__setattr__(self, "r_c", implied)
        return self

    def link_budget(self) -> LinkBudget:
        """The link budget of this radio, the model's defaults filled in."""
        cls = MEDIA.lookup(self.model, "radio.model")
        shadowing = self.shadowing_db if self.shadowing_db is not None else cls.default_shadowing_db
        wall = self.wall_db if self.wall_db is not None else DEFAULT_WALL_DB
        return LinkBudget(r_c=self.r_c, tx_dbm=self.tx_dbm, pl0_db=self.pl0_db,
                          exponent=self.path_loss_exponent or cls.default_exponent,
                          wall_db=wall if cls.uses_walls else 0.0,
                          shadowing_db=shadowing if cls.uses_shadowing else 0.0,
                          shadowing_corr_m=self.shadowing_corr_m)


class BaseStationSpec(_Strict):
    """A base station: its immobile reference node and the region its routers start in."""

    x: FiniteFloat
    y: FiniteFloat
    region: tuple[PositiveFloat, PositiveFloat] = (1.0, 1.0)
    robot: RobotRef = "amigobot"


class RoutersSpec(_Strict):
    """The routers of the AMRoNet."""

    count: Annotated[StrictInt, Field(ge=0)] = 30
    robot: RobotRef = "bebot"
    start: Literal["base", "uniform"] = "base"
    """``base``: in the base stations' regions (the paper); ``uniform``: scattered over the reachable free space
    (dropped from the air; used by the benchmark)."""


class AgentsSpec(_Strict):
    """The agents: fast explorers that use (and, in agent-assisted deployment, build) the AMRoNet."""

    per_base: Annotated[StrictInt, Field(ge=0)] = 0
    """Agents per base station; they start next to its reference node with its status."""
    robot: RobotRef = "pioneer"
    routers_carried: Annotated[StrictInt, Field(ge=0)] | None = None
    """Routers each agent carries; ``null`` for unlimited (DARPA SubT robots carried 6 to 12)."""
    when_empty: Literal["tether", "continue"] = "tether"
    """An agent with no router left: ``tether`` turns back when it is about to lose its last reference (it never
    loses its connection); ``continue`` goes on exploring and is cut off (the outage is counted)."""
    drop_settle_s: NonNegativeFloat = 0.0
    """Seconds after it is put down before a router relays and serves as a reference (DARPA SubT: 3 s)."""
    reverse_drop: PositiveFloat | None = None
    """Seconds out of contact after which an agent backs up along its own path until contact returns and drops a
    router there (MARBLE's reverse drop); ``null``: off."""
    trajectories: Annotated[str, Field(min_length=1)] | None = None
    """A CSV of timed waypoints the agents follow instead of exploring (agent-assisted deployment only): columns
    ``t, agent, x, y`` (seconds from the start of the run, the agent's index, metres in the map's frame). Agent
    ``k`` is the ``k``-th agent created: base station ``b``'s agents are ``b * per_base .. (b + 1) * per_base - 1``,
    in the order of ``base_stations``; agents without rows explore with ``algorithm.params.explorer``. A relative
    path is taken from the scenario file's folder (the working folder for a preset or a mapping) and recorded as an
    absolute one (:meth:`Scenario.to_dict`). The file must exist when the scenario is loaded; it is read and
    checked against the map when the run is set up (:mod:`amronet.world.trajectories`), following in
    :mod:`amronet.algorithms.agent_assisted.explorers.trajectory`. ``null``: the agents explore."""


class SimSpec(_Strict):
    """The simulation loop."""

    dt: PositiveFloat = 0.1
    time_limit: PositiveFloat = 300.0
    record_every: Annotated[StrictInt, Field(ge=1)] = 10
    coverage_target: float | str | None = None
    """Coverage at which a run ends, in (0, 1]; ``null``: the algorithm's default (0.99 for agent-assisted deployment,
    none for the others); ``off``: none (the run goes on until it settles or reaches its time limit)."""
    coverage_method: Literal["raster", "exact"] = "raster"
    stop_when_settled: StrictBool = True
    robot_collisions: StrictBool = True

    @field_validator("coverage_target", mode="before")
    @classmethod
    def _target(cls, value: Any) -> Any:
        ok = value is None or value == "off" or (
            isinstance(value, float) and math.isfinite(value) and 0 < value <= 1)
        if not ok:
            raise ValueError(f"@sim.coverage_target@{value!r} is not a fraction in (0, 1] (with a decimal point) "
                             "nor off; give e.g. 0.99, or off for no target")
        return value


class FaultSpec(_Strict):
    """One entry of ``faults``: nodes that fail (they stop sending and relaying and stay where they are).

    Exactly one of ``routers`` (this fraction of the routers deployed at ``at``, drawn by the run's generator),
    ``ids`` (these nodes, at ``at``), ``base_station`` (this base station's reference node, at ``at``) or
    ``rate_per_hour`` (every deployed router fails as a Poisson process of this rate, from ``at`` on, default 0).
    """

    at: NonNegativeFloat | None = None
    routers: Annotated[float, Field(strict=True, gt=0, le=1, allow_inf_nan=False)] | None = None
    ids: Annotated[list[Annotated[StrictInt, Field(ge=0)]], Field(min_length=1)] | None = None
    rate_per_hour: PositiveFloat | None = None
    base_station: Annotated[StrictInt, Field(ge=0)] | None = None

    @property
    def kind(self) -> str:
        """Which of the four kinds the entry is (``routers``, ``ids``, ``rate_per_hour``, ``base_station``)."""
        return next(k for k in FAULT_KINDS if getattr(self, k) is not None)


FAULT_KINDS = ("routers", "ids", "rate_per_hour", "base_station")


class AlgorithmSpec(_Strict):
    """Which deployment algorithm runs, with its own parameters (validated by the algorithm)."""

    name: str = "self-spreading"
    params: dict[str, Any] = Field(default_factory=dict)


class Scenario(_Strict):
    """A whole run, validated.

    Attributes:
        base_dir: Folder that relative paths (the map, ``agents.trajectories``) are resolved against; not part of
            the YAML.
    """

    name: str = "unnamed"
    description: str = ""
    map: str
    algorithm: AlgorithmSpec = Field(default_factory=AlgorithmSpec)
    radio: RadioSpec = Field(default_factory=RadioSpec)
    base_stations: Annotated[list[BaseStationSpec], Field(min_length=1)]
    routers: RoutersSpec = Field(default_factory=RoutersSpec)
    agents: AgentsSpec = Field(default_factory=AgentsSpec)
    sim: SimSpec = Field(default_factory=SimSpec)
    faults: list[FaultSpec] = Field(default_factory=list)
    """Node failures (:class:`FaultSpec`); none by default."""
    base_dir: str | None = Field(default=None, exclude=True)

    @model_validator(mode="after")
    def _check_algorithm(self) -> Scenario:
        if self.algorithm.name not in ALGORITHMS:
            raise ValueError(
                f"@algorithm.name@unknown algorithm {self.algorithm.name!r}; choose one of: "
                + ", ".join(sorted(ALGORITHMS))
            )
        if self.radio.model not in MEDIA:
            raise ValueError(f"@radio.model@unknown radio model {self.radio.model!r}; choose one of: "
                             + ", ".join(sorted(MEDIA)))
        for k, fault in enumerate(self.faults):
            kinds = [name for name in FAULT_KINDS if getattr(fault, name) is not None]
            if len(kinds) != 1:
                raise ValueError(f"@faults[{k}]@give exactly one of {', '.join(FAULT_KINDS)}, got "
                                 + (", ".join(kinds) or "none") + "; e.g. {at: 120, routers: 0.2}")
            if kinds[0] != "rate_per_hour" and fault.at is None:
                raise ValueError(f"@faults[{k}].at@required: the time in seconds at which the {kinds[0]} fail(s)")
            if fault.base_station is not None and fault.base_station >= len(self.base_stations):
                raise ValueError(f"@faults[{k}].base_station@no base station {fault.base_station}; the scenario has "
                                 f"{len(self.base_stations)} (numbered from 0)")
        self._check_trajectories()
        if self.radio.model != "unit-disk" and self.sim.coverage_method != "raster":
            raise ValueError(f"@sim.coverage_method@{self.sim.coverage_method!r} is defined for the unit disk only; "
                             f"coverage under {self.radio.model} is decided cell by cell: use raster")
        return self

    def _check_trajectories(self) -> None:
        path = self.trajectories_path()
        if path is None:
            return
        given = self.agents.trajectories
        if not ALGORITHMS[self.algorithm.name].follows_paths:
            takers = ", ".join(sorted(name for name, cls in ALGORITHMS.items() if cls.follows_paths))
            raise ValueError(f"@agents.trajectories@{self.algorithm.name} does not move agents along paths; use "
                             f"algorithm.name {takers} or leave agents.trajectories out")
        if self.agents.per_base < 1:
            raise ValueError("@agents.trajectories@the scenario has no agents to follow the paths; set "
                             "agents.per_base >= 1")
        if not path.is_file():
            where = f" (taken from {self.base_dir})" if self.base_dir and not Path(str(given)).is_absolute() else ""
            raise ValueError(f"@agents.trajectories@no file {given!r}{where}; give the path of a CSV with columns "
                             "t, agent, x, y (a relative path is taken from the scenario file's folder)")

    def trajectories_path(self) -> Path | None:
        """The agents' trajectory file (``agents.trajectories``) with a relative path resolved; ``None``: none."""
        given = self.agents.trajectories
        if given is None:
            return None
        path = Path(given).expanduser()
        if self.base_dir and not path.is_absolute():
            path = Path(self.base_dir) / path
        return path

    def algorithm_params(self) -> BaseModel:
        """The algorithm's parameters, validated by the algorithm's own parameter model."""
        model = ALGORITHMS[self.algorithm.name].Params
        try:
            return model.model_validate(self.algorithm.params)
        except ValidationError as exc:
            raise to_scenario_error(exc, prefix="algorithm.params", model=model) from None

    def to_dict(self) -> dict[str, Any]:
        """The scenario as plain data (what a YAML file would hold).

        A trajectory file (``agents.trajectories``) is given by its absolute path, so the data means the same file
        wherever it is loaded from (a run's ``summary.json``, a copy with overrides).
        """
        data = self.model_dump(mode="json", exclude={"base_dir"})
        path = self.trajectories_path()
        if path is not None:
            data["agents"]["trajectories"] = str(path.resolve())
        return data

    def with_overrides(self, overrides: dict[str, Any]) -> Scenario:
        """A copy with dotted-path fields replaced, e.g. ``{"radio.r_c": 1.5, "routers.count": 60}``."""
        data = apply_overrides(self.to_dict(), overrides)
        return _validate(data, base_dir=self.base_dir)


_UNION_TAGS = ("name", "spec")
"""The tags of :data:`RobotRef`'s two forms: pydantic puts them into an error's location after ``robot``."""


def _field_path(loc: tuple[Any, ...], prefix: str = "") -> str:
    path = prefix
    for k, part in enumerate(loc):
        if isinstance(part, int):
            path += f"[{part}]"
        elif not (part in _UNION_TAGS and k > 0 and loc[k - 1] == "robot"):
            path += ("." if path else "") + str(part)
    return path


def _allowed_keys(model: type[BaseModel], loc: tuple[Any, ...]) -> list[str]:
    current: Any = model
    for k, part in enumerate(loc[:-1]):
        if isinstance(part, int) or (part in _UNION_TAGS and k > 0 and loc[k - 1] == "robot"):
            continue
        field = getattr(current, "model_fields", {}).get(part)
        if field is None:
            return []
        found = _model_in(field.annotation)
        if found is not None:
            current = found
    return [k for k in getattr(current, "model_fields", {}) if k != "base_dir"]


def _model_in(annotation: Any, depth: int = 0) -> type[BaseModel] | None:
    """The first pydantic model inside an annotation (through unions, ``Annotated`` and containers)."""
    if isinstance(annotation, type) and issubclass(annotation, BaseModel):
        return annotation
    if depth > 4:
        return None
    for inner in getattr(annotation, "__args__", ()) or ():
        found = _model_in(inner, depth + 1)
        if found is not None:
            return found
    origin = getattr(annotation, "__origin__", None)
    return _model_in(origin, depth + 1) if origin is not None and origin is not annotation else None


def to_scenario_error(exc: ValidationError, prefix: str = "", model: type[BaseModel] = Scenario) -> ScenarioError:
    err = exc.errors()[0]
    msg = str(err.get("msg", "invalid"))
    if msg.startswith("Value error, @"):
        _, field, text = msg.split("@", 2)
        return ScenarioError(field, text)
    loc = tuple(err.get("loc", ()))
    field = _field_path(loc, prefix)
    if err.get("type") == "extra_forbidden":
        allowed = _allowed_keys(model, loc)
        return ScenarioError(field, "unknown key; allowed keys here: " + ", ".join(allowed))
    if err.get("type") == "missing":
        return ScenarioError(field, "required field is missing; add it")
    got = err.get("input")
    shown = repr(got) if not isinstance(got, dict | list) else type(got).__name__
    if isinstance(got, float) and math.isnan(got):
        shown = "nan"
    return ScenarioError(field, f"{msg[0].lower()}{msg[1:]} (got {shown})")


def _validate(data: Any, base_dir: str | None) -> Scenario:
    if not isinstance(data, dict):
        raise ScenarioError("scenario", f"must be a mapping of fields, got {type(data).__name__}")
    try:
        scenario = Scenario.model_validate({**data, "base_dir": base_dir})
    except ValidationError as exc:
        raise to_scenario_error(exc) from None
    scenario.algorithm_params()
    return scenario


def parse_override(text: str) -> tuple[str, Any]:
    """Parse one ``--set key=value`` item; the value is YAML (``1e-3``, ``true``, ``[1, 2]``; :func:`load_yaml`)."""
    key, sep, value = text.partition("=")
    if not sep or not key.strip():
        raise ScenarioError("--set", f"expected KEY=VALUE such as radio.r_c=1.5, got {text!r}")
    return key.strip(), load_yaml(value, key.strip(), f"value {value!r}")


def apply_overrides(data: dict[str, Any], overrides: dict[str, Any]) -> dict[str, Any]:
    """Return a copy of ``data`` with dotted paths set (list items by index: ``base_stations.0.x``).

    One rule for every caller (``run --set``, sweeps, the library): an ``algorithm.name`` that switches to another
    algorithm drops the base's ``algorithm.params`` first, since they belong to the base's algorithm; the new one
    starts from its defaults and ``algorithm.params[.KEY]`` given in ``overrides`` apply on top. The same for the
    radio: ``radio.threshold_dbm`` given without ``radio.r_c`` replaces the base's ``r_c`` (and the other way round),
    and a ``radio.model`` that switches drops the base's ``wall_db`` / ``shadowing_db`` that the new model does not
    take.
    """
    out = copy.deepcopy(data)
    radio = out.get("radio") if isinstance(out, dict) else None
    if isinstance(radio, dict) and not isinstance(overrides.get("radio"), dict):
        for given, replaced in (("threshold_dbm", "r_c"), ("r_c", "threshold_dbm")):
            if f"radio.{given}" in overrides and f"radio.{replaced}" not in overrides:
                radio.pop(replaced, None)
        new_model = MEDIA.get(overrides.get("radio.model")) if isinstance(overrides.get("radio.model"), str) else None
        if new_model is not None and overrides["radio.model"] != radio.get("model"):
            for key, taken in (("wall_db", new_model.uses_walls), ("shadowing_db", new_model.uses_shadowing)):
                if not taken and f"radio.{key}" not in overrides:
                    radio.pop(key, None)
    algorithm = out.get("algorithm") if isinstance(out, dict) else None
    name = overrides.get("algorithm.name")
    if (isinstance(algorithm, dict) and name is not None and name != algorithm.get("name")
            and not isinstance(overrides.get("algorithm"), dict)):
        algorithm.pop("params", None)
    for dotted, value in overrides.items():
        parts = dotted.split(".")
        node: Any = out
        for i, part in enumerate(parts):
            last = i == len(parts) - 1
            if isinstance(node, list):
                if not part.isdigit() or int(part) >= len(node):
                    raise ScenarioError(".".join(parts[: i + 1]), f"no list item {part}; the list has {len(node)}")
                key: Any = int(part)
            elif isinstance(node, dict):
                key = part
            else:
                raise ScenarioError(".".join(parts[:i]), "is not a mapping; cannot set a field inside it")
            if last:
                node[key] = value
            else:
                if isinstance(node, dict) and key not in node:
                    node[key] = {}
                node = node[key]
    return out


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
        ScenarioError: The source cannot be read or is invalid; the message names the field.
    """
    base_dir: str | None = None
    if isinstance(source, Scenario):
        data, base_dir = source.to_dict(), source.base_dir
    elif isinstance(source, dict):
        data = source
    elif not isinstance(source, str | Path):
        raise ScenarioError("scenario", f"must be a mapping of fields, a YAML path or a preset name, got "
                                        f"{type(source).__name__}")
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
    if overrides:
        data = apply_overrides(data if isinstance(data, dict) else {}, overrides)
    return _validate(data, base_dir)
