"""What a drop rule is: the agents' decision *when* to put a router down, from what an agent knows.

Agent-assisted deployment (:mod:`amronet.algorithms.agent_assisted.controller`) asks its drop rule once per step which
agents
release a reference router now. The rule sees an :class:`AgentView`: per agent, what its radio hears of the
references (deployed nodes: base reference nodes and deployed routers) and what its own odometry and range scan
say. *Where* the router goes (next to the agent, on its reference's side) and triangular deployment are the
controller's, the same for every rule.

A rule declares what it reads (:attr:`DropRule.reads_positions`, :attr:`DropRule.needs_contact`,
:attr:`DropRule.needs_scans`), so that location-free rules can be tested to give the same decisions when positions
are perturbed and the radio is not, and so that the controller computes the agents' contact with a base station
only when a rule asks.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from dataclasses import dataclass
from typing import ClassVar

import numpy as np
from pydantic import BaseModel, ConfigDict, ValidationError

from amronet.algorithms.agent_assisted.rule_kernels import nearest_distances
from amronet.registry import Registry

__all__ = ["DROP_RULES", "AgentView", "DropContext", "DropRule", "NoParams", "validate_drop_params"]


class NoParams(BaseModel):
    """A rule without parameters."""

    model_config = ConfigDict(extra="forbid", frozen=True)


@dataclass(frozen=True)
class DropContext:
    """What a rule is told once, when the run starts.

    Attributes:
        r_c: The radio's range (median range without walls and shadowing), metres.
        r_eff: The paper's "about to lose" distance ``(1 - loss_margin) r_c``.
        dt: Step length, seconds.
        n_agents: Number of agents.
        sensor_range: Maximum reading of the agents' range sensors, metres.
    """

    r_c: float
    r_eff: float
    dt: float
    n_agents: int
    sensor_range: float


@dataclass(frozen=True)
class AgentView:
    """What the agents know this step, arrays aligned with the agents (``A`` of them).

    Attributes:
        t: Simulated time, seconds.
        current: Each agent's current reference (a node id), -1 when it hears none.
        nearest_d: Distance to the nearest reference it hears (radio ranging), ``inf`` when none.
        best_margin: Best link margin (dB above the usable threshold) to a reference it hears, ``-inf`` when none.
        xy: Each agent's own position (odometry) ``(A, 2)``.
        heading: Each agent's heading, radians.
        relay_xy: Positions of the known relays (every deployed node, base nodes included; the team shares
            where relays were put down) ``(R, 2)``.
        base_xy: Positions of the base reference nodes ``(B, 2)``.
        in_contact: Whether each agent has a path to a base station through the network (``None`` unless the
            rule asks, :attr:`DropRule.needs_contact`).
        scans: The agents' range readings ``(A, n_beams)``, beam 0 along the heading (``None`` unless the rule
            asks, :attr:`DropRule.needs_scans`).
        can_drop: Agents that carry a router and whose previous drop is not still settling.
    """

    t: float
    current: np.ndarray
    nearest_d: np.ndarray
    best_margin: np.ndarray
    xy: np.ndarray
    heading: np.ndarray
    relay_xy: np.ndarray
    base_xy: np.ndarray
    in_contact: np.ndarray | None
    scans: np.ndarray | None
    can_drop: np.ndarray

    def nearest_relay_distance(self, among: np.ndarray | None = None) -> np.ndarray:
        """Straight-line distance from each agent to the nearest known relay (``among``: those positions instead)."""
        pts = self.relay_xy if among is None else among
        if len(pts) == 0:
            return np.full(len(self.xy), np.inf)
        out = np.empty(len(self.xy))  # (a compiled loop: the distances NumPy's broadcast gives, bit for bit)
        nearest_distances(np.ascontiguousarray(self.xy, dtype=np.float64), np.ascontiguousarray(pts, dtype=np.float64),
                          out)
        return out


class DropRule(ABC):
    """Base class of drop rules.

    Args:
        params: Validated parameters (an instance of :attr:`Params`).
        context: What the rule is told when the run starts.
    """

    name: ClassVar[str]
    Params: ClassVar[type[BaseModel]] = NoParams
    reads_positions: ClassVar[bool] = True
    """Whether decisions read positions (``xy``, ``relay_xy``, ``base_xy``, ``nearest_d``); ``False``: location-free."""
    needs_contact: ClassVar[bool] = False
    """Whether decisions read :attr:`AgentView.in_contact`."""
    needs_scans: ClassVar[bool] = False
    """Whether decisions read :attr:`AgentView.scans`."""
    near_reference: ClassVar[bool] = True
    """Whether a router must be put down within ``r_c`` of the agent's current reference (the paper's placement)."""
    drives_to_goal: ClassVar[bool] = False
    """Whether a router put down drives on to a goal point the rule picks (:meth:`goal`)."""

    def __init__(self, params: BaseModel, context: DropContext) -> None:
        self.params = params
        self.context = context

    @abstractmethod
    def decide(self, view: AgentView) -> np.ndarray:
        """Which agents release a reference router now ``(A,)`` (only agents with ``view.can_drop`` may)."""

    def losing(self, view: AgentView) -> np.ndarray:
        """Which agents are about to lose their last reference ``(A,)``: a tethered agent turns back then.

        Default: the paper's, every reference heard is at least ``r_eff`` away.
        """
        return (view.current >= 0) & (view.nearest_d >= self.context.r_eff)

    def dropped(self, who: np.ndarray, view: AgentView) -> None:  # noqa: B027 - optional hook
        """Learn that the agents ``who`` (a mask ``(A,)``) released a router this step (default: ignore)."""

    def goal(self, spot: np.ndarray, reference_xy: np.ndarray, origin_xy: np.ndarray,
             taken_xy: np.ndarray) -> np.ndarray | None:
        """Where a router just put down at ``spot`` drives to, or ``None`` to stay (rules with :attr:`drives_to_goal`).

        Args:
            spot: Where it was put down ``(2,)``.
            reference_xy: The reference it was put down next to ``(2,)`` (it must stay linked to it).
            origin_xy: The base station whose status it takes ``(2,)``.
            taken_xy: Positions of the nodes already there and the goals other routers drive to ``(K, 2)``.
        """
        return None

    def keep_radius(self) -> float:
        """How far a router driving to its goal may get from the reference it was put down next to (metres)."""
        return self.context.r_eff

    def retries(self) -> int:
        """How many more goals a router blocked on its way to one tries before it stays where it is."""
        return 0

    def report(self) -> dict[str, object]:
        """Rule-specific numbers for the run's summary (default: none)."""
        return {}


DROP_RULES: Registry[type[DropRule]] = Registry("drop rule")
"""Drop rules by name; a rule registers itself with ``@DROP_RULES.register(name)`` (``algorithm.params.drop_rule``)."""


def validate_drop_params(rule: type[DropRule], params: dict[str, object], field: str) -> BaseModel:
    """The rule's validated parameters.

    Raises:
        ValueError: Invalid parameters, as ``"@field.key@message"`` (the scenario's one-line error format).
    """
    try:
        return rule.Params.model_validate(params)
    except ValidationError as exc:
        err = exc.errors()[0]
        loc = ".".join(str(p) for p in err.get("loc", ()))
        where = f"{field}.{loc}" if loc else field
        msg = str(err.get("msg", "invalid"))
        if err.get("type") == "extra_forbidden":
            keys = ", ".join(rule.Params.model_fields) or "none"
            msg = f"unknown key for the {rule.name} rule; allowed keys here: {keys}"
        elif "input" in err and not isinstance(err["input"], dict | list):
            msg = f"{msg[0].lower()}{msg[1:]} (got {err['input']!r})"
        raise ValueError(f"@{where}@{msg}") from None
