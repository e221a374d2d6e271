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
    ConfigDict,
    Discriminator,
    Field,
    ModelWrapValidatorHandler,
    PrivateAttr,
    StrictInt,
    Tag,
    ValidationError,
    ValidationInfo,
    field_validator,
    model_validator,
)

from amronet.algorithms import ALGORITHMS
from amronet.engine.propagation import RADIO_BOUNDS, LinkBudget, median_range
from amronet.engine.radio import DEFAULT_WALL_DB, MEDIA
from amronet.errors import ScenarioError
from amronet.limits import MAX_COUNT
from amronet.scenario.defaults import fill_start_regions, with_algorithm_defaults, without
from amronet.scenario.messages import to_scenario_error
from amronet.scenario.overrides import apply_overrides
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

PositiveFloat = Annotated[float, Field(strict=True, gt=0, allow_inf_nan=False)]
NonNegativeFloat = Annotated[float, Field(strict=True, ge=0, allow_inf_nan=False)]
FiniteFloat = Annotated[float, Field(strict=True, allow_inf_nan=False)]
Count = Annotated[StrictInt, Field(ge=0, le=MAX_COUNT)]
"""A number of robots (at most :data:`~amronet.limits.MAX_COUNT`: larger ones are typos)."""
NodeId = Annotated[StrictInt, Field(ge=0, lt=MAX_COUNT)]

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
    packet_loss: YamlBool = False
    """Drop each link in each step with probability one minus its packet delivery ratio."""

    @field_validator(*RADIO_BOUNDS, mode="before")
    @classmethod
    def _in_bounds(cls, value: Any, info: ValidationInfo) -> Any:
        """Refuse a number outside the field's physical range (:data:`~amronet.engine.propagation.RADIO_BOUNDS`)."""
        problem = RADIO_BOUNDS[str(info.field_name)].problem(value)
        if problem is not None:
            raise ValueError(f"@radio.{info.field_name}@{problem}")
        return value

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
    """Width and height (m) of the rectangle around the base its robots start in; left out, the smallest square of
    at least 1 m that holds them (:mod:`amronet.scenario.defaults`)."""
    robot: RobotRef = "amigobot"


class RoutersSpec(_Strict):
    """The routers of the AMRoNet."""

    count: Count = 30
    robot: RobotRef = "bebot"
    start: Literal["base", "uniform"] = "base"
    """``base``: in the base stations' regions (the paper); ``uniform``: scattered over the reachable free space
    (dropped from the air; used by the benchmark)."""


class AgentsSpec(_Strict):
    """The agents: fast explorers that use (and, in agent-assisted deployment, build) the AMRoNet."""

    per_base: Count = 0
    """Agents per base station; they start next to its reference node with its status."""
    robot: RobotRef = "pioneer"
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


class SimSpec(_Strict):
    """The simulation loop."""

    dt: PositiveFloat = 0.1
    time_limit: PositiveFloat = 300.0
    record_every: Annotated[StrictInt, Field(ge=1, le=MAX_COUNT)] = 10
    coverage_target: float | str | None = None
    """Coverage at which a run ends, in (0, 1]; ``null``: the algorithm's default (0.99 for agent-assisted deployment,
    none for the others); ``off``: none (the run goes on until it settles or reaches its time limit)."""
    coverage_method: Literal["raster", "exact"] = "raster"
    stop_when_settled: YamlBool = True
    robot_collisions: YamlBool = True

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


class FaultSpec(_Strict):
    """One entry of ``faults``: nodes that fail (they stop sending and relaying and stay where they are).

    Exactly one of ``routers`` (this fraction of the routers deployed at ``at``, drawn by the run's generator),
    ``ids`` (these nodes, at ``at``), ``base_station`` (this base station's reference node, at ``at``) or
    ``rate_per_hour`` (every deployed router fails as a Poisson process of this rate, from ``at`` on, default 0).
    """

    at: NonNegativeFloat | None = None
    routers: Annotated[float, Field(strict=True, gt=0, le=1, allow_inf_nan=False)] | None = None
    ids: Annotated[list[NodeId], Field(min_length=1)] | None = None
    rate_per_hour: PositiveFloat | None = None
    base_station: NodeId | None = None

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
