"""The parameters of agent-assisted router deployment (:class:`AgentAssistedParams`) and its scenarios' defaults.

Light (no kernels): a scenario is checked before its run is set up (:mod:`amronet.algorithms.declaration`).
"""

from __future__ import annotations

from typing import Annotated, Any, Literal

from pydantic import BaseModel, ConfigDict, Field, StrictInt, model_validator

from amronet.algorithms.common.param_types import TriangularMode
from amronet.limits import MAX_COUNT

__all__ = ["DEFAULT_COVERAGE_TARGET", "DEFAULT_EXPLORER", "SCENARIO_DEFAULTS", "AgentAssistedParams"]

DEFAULT_COVERAGE_TARGET = 0.99

SCENARIO_DEFAULTS = {"routers.count": 0, "agents.per_base": 3, "radio.r_c": 6.0}
"""What a scenario of agent-assisted deployment leaves out defaults to: agents release the routers (no free ones),
three of them per base station, and the range of the paper's agent-assisted setups (5.1): with the schema's 1 m an
agent's step at the default ``sim.dt`` spans the whole 'about to lose' band."""

DEFAULT_EXPLORER = "frontier"
"""The agents' explorer unless a scenario names one: the one that finishes on real floor plans.

The paper's ``random`` reads a doorway narrower than twice its ``avoid_range`` (1.2 m) as a wall and stays in the
rooms it starts in (:mod:`~amronet.algorithms.agent_assisted.explorers.random_walk`). Measured with 3 agents per
base station, at most 1 800 s, seeds 1-5, on six floors with 1.0-1.2 m doors (docs/agent-assisted.md, *Which explorer by
default*): ``frontier`` reached 99 % in all 30 runs, 95 % after 30-655 s; ``random-escape`` reached 95 % in 29 and
took 1.5 to 10 times as long; ``wall-follow`` stayed below 95 % in every run on four floors, ``random`` on five.
The paper's figures and the golden runs name their explorer, so they do not depend on this default.
"""


class AgentAssistedParams(BaseModel):
    """Parameters of agent-assisted router deployment.

    Attributes:
        triangular: ``off``, ``none``, ``global`` or ``local`` (see :mod:`amronet.algorithms.common.triangular`).
        loss_margin: Width of the "about to lose" band as a fraction of ``r_c``.
        explorer: Exploration strategy of the agents (:data:`amronet.algorithms.agent_assisted.explorers.EXPLORERS`):
            :data:`DEFAULT_EXPLORER` unless given; ``random`` is the paper's.
        turn_noise: Heading noise of the agents' random exploration, radians per square-root second.
        avoid_range: Sonar readings nearer than this (metres) make an agent turn away.
        give_up_steps: Consecutive blocked steps after which a triangle router stops short of its goal.
        release_gap: Gap in metres between an agent's body and the router it releases.
        drop_rule: When an agent puts a router down (:data:`amronet.algorithms.agent_assisted.drops.DROP_RULES`); the
        paper's
            ``last-reference`` by default.
        drop: The drop rule's own parameters (e.g. ``{drop_margin_db: 3}`` for ``link-quality``).
        repair: ``none``; ``relocate``: deployed routers that a failure cut off move toward where the lost
            neighbour stood (:mod:`amronet.algorithms.agent_assisted.relocate`); ``retrace``: they back up the way
            they were carried in until their routing finds a base station again, which works behind walls
            (:mod:`amronet.algorithms.agent_assisted.retrace`).
        repair_confirm_s: How long a neighbour must be missing before a router counts it as lost, seconds.
    """

    model_config = ConfigDict(extra="forbid", frozen=True)

    triangular: TriangularMode = "local"
    loss_margin: Annotated[float, Field(strict=True, gt=0, lt=0.5, allow_inf_nan=False)] = 0.05
    explorer: str = DEFAULT_EXPLORER
    turn_noise: Annotated[float, Field(strict=True, ge=0, allow_inf_nan=False)] = 0.5
    avoid_range: Annotated[float, Field(strict=True, gt=0, allow_inf_nan=False)] = 0.6
    give_up_steps: Annotated[StrictInt, Field(ge=1, le=MAX_COUNT)] = 20
    release_gap: Annotated[float, Field(strict=True, ge=0, allow_inf_nan=False)] = 0.02
    drop_rule: str = "last-reference"
    drop: dict[str, Any] = Field(default_factory=dict)
    repair: Literal["none", "relocate", "retrace"] = "none"
    repair_confirm_s: Annotated[float, Field(strict=True, ge=0, le=600, allow_inf_nan=False)] = 1.0

    @model_validator(mode="after")
    def _check_drop_rule(self) -> AgentAssistedParams:
        from amronet.algorithms.agent_assisted.drops import DROP_RULES, validate_drop_params  # (kernels)

        rule = DROP_RULES.get(self.drop_rule)
        if rule is None:
            raise ValueError(f"@algorithm.params.drop_rule@unknown drop rule {self.drop_rule!r}; choose one of: "
                             + ", ".join(sorted(DROP_RULES)))
        validate_drop_params(rule, self.drop, "algorithm.params.drop")
        return self

