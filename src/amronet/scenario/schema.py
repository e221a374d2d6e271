"""The scenario's schema: every field of a scenario file, its type, its default and its checks.

Unknown keys, wrong types, NaN or negative radii and speeds are rejected with one line that names the field
(:mod:`amronet.scenario.messages`).
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Annotated, Any, Literal

from pydantic import (
    BaseModel,
    Discriminator,
    Field,
    ModelWrapValidatorHandler,
    PrivateAttr,
    StrictInt,
    Tag,
    ValidationError,
    field_validator,
    model_validator,
)

from amronet.algorithms.declaration import ALGORITHMS, declaration_of
from amronet.engine.radio_traits import model_names, traits_of
from amronet.errors import ScenarioError
from amronet.limits import MAX_COUNT
from amronet.scenario.defaults import fill_start_regions, with_algorithm_defaults, without
from amronet.scenario.fields import MAX_RANGE_M, Count, FiniteFloat, NodeId, NonNegativeFloat, PositiveFloat, Strict
from amronet.scenario.messages import to_scenario_error
from amronet.scenario.overrides import apply_overrides
from amronet.scenario.radio_spec import RadioSpec
from amronet.yaml_fields import YamlBool

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
    "validate_scenario",
]


class RobotSpec(Strict):
    """A robot model given field by field instead of by name."""

    radius: PositiveFloat
    """Body radius (m)."""
    max_speed: NonNegativeFloat
    """Top speed (m/s); 0 for an immobile node."""
    sensor_beams: Annotated[StrictInt, Field(ge=1, le=360)]
    """Range sensors, evenly spaced around the body."""
    sensor_range: PositiveFloat
    """Range of each sensor (m)."""


def _robot_ref_tag(value: Any) -> str:
    return "spec" if isinstance(value, dict | RobotSpec) else "name"


RobotRef = Annotated[Annotated[str, Tag("name")] | Annotated[RobotSpec, Tag("spec")], Discriminator(_robot_ref_tag)]
"""A robot model by name (``bebot``), or field by field (a mapping: errors then name the field inside it)."""


class BaseStationSpec(Strict):
    """A base station: its immobile reference node and the region its routers start in."""

    x: FiniteFloat
    """Position of the base station's reference node (m, in the map's frame)."""
    y: FiniteFloat
    """Position of the base station's reference node (m, in the map's frame)."""
    region: tuple[PositiveFloat, PositiveFloat] = (1.0, 1.0)
    """Width and height (m) of the rectangle around the base its robots start in; left out, the smallest square of
    at least 1 m that holds them (:mod:`amronet.scenario.defaults`)."""
    robot: RobotRef = "amigobot"
    """The reference node's robot model (immobile)."""


class RoutersSpec(Strict):
    """The routers of the AMRoNet."""

    count: Count = 30
    """Free routers that start at the base stations (agent-assisted deployment: 0 unless given; agents carry
    them)."""
    robot: RobotRef = "bebot"
    """The routers' robot model."""
    start: Literal["base", "uniform"] = "base"
    """``base``: in the base stations' regions (the paper); ``uniform``: scattered over the reachable free space
    (dropped from the air; used by the benchmark)."""


class AgentsSpec(Strict):
    """The agents: fast explorers that use (and, in agent-assisted deployment, build) the AMRoNet."""

    per_base: Count = 0
    """Agents per base station; they start next to its reference node with its status."""
    robot: RobotRef = "pioneer"
    """The agents' robot model."""
    routers_carried: Count | None = None
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


class SimSpec(Strict):
    """The simulation loop."""

    dt: PositiveFloat = 0.1
    """Simulated seconds per step."""
    time_limit: PositiveFloat = 300.0
    """Simulated seconds after which a run stops (truncated)."""
    record_every: Annotated[StrictInt, Field(ge=1, le=MAX_COUNT)] = 10
    """Steps between two recorded rows of the time series (and frames of a recording)."""
    coverage_target: float | str | None = None
    """Coverage at which a run ends, in (0, 1]; ``null``: the algorithm's default (0.99 for agent-assisted deployment,
    none for the others); ``off``: none (the run goes on until it settles or reaches its time limit)."""
    coverage_method: Literal["raster", "exact"] = "raster"
    """``raster``: coverage counted cell by cell on the map's grid; ``exact``: the union of disks in closed form
    (unit disk only)."""
    stop_when_settled: YamlBool = True
    """End the run when no router can move any more."""
    robot_collisions: YamlBool = True
    """Robots' bodies block each other (as well as walls)."""

    @field_validator("coverage_target", mode="before")
    @classmethod
    def _target(cls, value: Any) -> Any:
        ok = value is None or value == "off" or (
            isinstance(value, float) and math.isfinite(value) and 0 < value <= 1)
        if not ok:
            shown = f"a {type(value).__name__}" if isinstance(value, list | dict) else repr(value)
            raise ValueError(f"@sim.coverage_target@{shown} is not a fraction in (0, 1] (with a decimal point) "
                             "nor off; give e.g. 0.99, or off for no target")
        return value


class FaultSpec(Strict):
    """One entry of ``faults``: nodes that fail (they stop sending and relaying and stay where they are).

    Exactly one of ``routers`` (this fraction of the routers deployed at ``at``, drawn by the run's generator),
    ``ids`` (these nodes, at ``at``), ``base_station`` (this base station's reference node, at ``at``) or
    ``rate_per_hour`` (every deployed router fails as a Poisson process of this rate, from ``at`` on, default 0).
    """

    at: NonNegativeFloat | None = None
    """Time (s) at which the nodes fail (for ``rate_per_hour``: from when failures start; default 0)."""
    routers: Annotated[float, Field(strict=True, gt=0, le=1, allow_inf_nan=False)] | None = None
    """Fraction of the routers deployed at ``at`` that fail, drawn by the run's generator."""
    ids: Annotated[list[NodeId], Field(min_length=1)] | None = None
    """The node ids that fail at ``at``."""
    rate_per_hour: PositiveFloat | None = None
    """Each deployed router fails as a Poisson process of this rate (per hour)."""
    base_station: NodeId | None = None
    """Index of the base station whose reference node fails at ``at``."""

    @property
    def kind(self) -> str:
        """Which of the four kinds the entry is (``routers``, ``ids``, ``rate_per_hour``, ``base_station``)."""
        return next(k for k in FAULT_KINDS if getattr(self, k) is not None)


FAULT_KINDS = ("routers", "ids", "rate_per_hour", "base_station")


class AlgorithmSpec(Strict):
    """Which deployment algorithm runs, with its own parameters (validated by the algorithm)."""

    name: str = "self-spreading"
    """The deployment algorithm (its registry name)."""
    params: dict[str, Any] = Field(default_factory=dict)
    """The algorithm's own parameters (see its section below); unknown ones are errors."""


class Scenario(Strict):
    """A whole run, validated.

    Attributes:
        base_dir: Folder that relative paths (the map, ``agents.trajectories``) are resolved against; not part of
            the YAML.
    """

    name: str = "unnamed"
    """A name for the scenario (goes into the outputs)."""
    description: str = ""
    """One line saying what the scenario is for."""
    map: str
    """A built-in map (``amronet maps list``) or the path of a ROS ``map_server`` YAML file."""
    algorithm: AlgorithmSpec = Field(default_factory=AlgorithmSpec)
    """Which algorithm runs, with its parameters."""
    radio: RadioSpec = Field(default_factory=RadioSpec)
    """The radio medium."""
    base_stations: Annotated[list[BaseStationSpec], Field(min_length=1)]
    """The base stations, at least one; each has an immobile reference node."""
    routers: RoutersSpec = Field(default_factory=RoutersSpec)
    """The free routers."""
    agents: AgentsSpec = Field(default_factory=AgentsSpec)
    """The agents."""
    sim: SimSpec = Field(default_factory=SimSpec)
    """The simulation loop."""
    faults: list[FaultSpec] = Field(default_factory=list)
    """Node failures (:class:`FaultSpec`); none by default."""
    base_dir: str | None = Field(default=None, exclude=True)

    _defaulted: frozenset[str] = PrivateAttr(default=frozenset())
    """Fields that took a default following the rest of the scenario (:mod:`amronet.scenario.defaults`)."""

    @model_validator(mode="wrap")
    @classmethod
    def _fitting_defaults(cls, data: Any, handler: ModelWrapValidatorHandler[Scenario]) -> Scenario:
        data, filled = with_algorithm_defaults(data)
        scenario = handler(data)
        scenario._defaulted = frozenset(filled) | frozenset(fill_start_regions(scenario))
        return scenario

    @model_validator(mode="after")
    def _check_algorithm(self) -> Scenario:
        if self.algorithm.name not in ALGORITHMS:
            raise ValueError(
                f"@algorithm.name@unknown algorithm {self.algorithm.name!r}; choose one of: "
                + ", ".join(sorted(ALGORITHMS))
            )
        if traits_of(self.radio.model) is None:
            raise ValueError(f"@radio.model@unknown radio model {self.radio.model!r}; choose one of: "
                             + ", ".join(model_names()))
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
        if not declaration_of(self.algorithm.name).follows_paths:
            takers = ", ".join(sorted(name for name in ALGORITHMS if declaration_of(name).follows_paths))
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
        model = declaration_of(self.algorithm.name).params
        try:
            return model.model_validate(self.algorithm.params)
        except ValidationError as exc:
            raise to_scenario_error(exc, model=model, prefix="algorithm.params") from None

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

    def given_dict(self) -> dict[str, Any]:
        """:meth:`to_dict` less the defaults that follow the rest of the scenario, which a change computes again."""
        return without(self.to_dict(), self._defaulted)

    def with_overrides(self, overrides: dict[str, Any]) -> Scenario:
        """A copy with dotted-path fields replaced, e.g. ``{"radio.r_c": 1.5, "routers.count": 60}``."""
        data = apply_overrides(self.given_dict(), overrides)
        return validate_scenario(data, base_dir=self.base_dir)


def validate_scenario(data: Any, base_dir: str | None) -> Scenario:
    """Validate plain data as a scenario, its algorithm's parameters too; ``base_dir``: see :class:`Scenario`.

    Raises:
        ScenarioError: The data is not a valid scenario; the message names the field.
    """
    if not isinstance(data, dict):
        raise ScenarioError("scenario", f"must be a mapping of fields, got {type(data).__name__}")
    try:
        scenario = Scenario.model_validate({**data, "base_dir": base_dir})
    except ValidationError as exc:
        raise to_scenario_error(exc, model=Scenario) from None
    scenario.algorithm_params()
    return scenario
