"""Robot models and roles, and the swarm state arrays.

Every robot of a run is one row of the arrays in :class:`Swarm`. Its *role* (:class:`Role`: base-station
reference node, router, agent) and its *state* are small integer codes, so that a simulation step is a handful
of vectorized operations; :data:`ROLE_NAMES` and :data:`STATE_NAMES` turn them into the strings written to files
(where the role is the field ``kind``). Its *robot model* (:class:`RobotModel`: footprint, speed, sensors) is
an index into :attr:`Swarm.models`.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

import numpy as np
from numba import njit

from amronet.engine.robot_models import AMIGOBOT, BEBOT, PIONEER, ROBOT_MODELS, RobotModel

__all__ = [
    "AMIGOBOT",
    "BEBOT",
    "DEPLOYED_STATES",
    "MOBILE_STATES",
    "PIONEER",
    "ROBOT_MODELS",
    "ROLE_NAMES",
    "SETTLING_STATES",
    "STATE_NAMES",
    "RobotModel",
    "Role",
    "State",
    "Swarm",
    "state_lookup",
]


class Role:
    """Role of a robot in the two-tier network.

    Plain ``int`` codes, not an ``IntEnum``: NumPy compares an array with an enum member several times slower
    than with an ``int``, and a step makes many such comparisons.
    """

    BASE = 0
    """Immobile reference node of a base station."""
    ROUTER = 1
    """Small, slow robot that forms the AMRoNet."""
    AGENT = 2
    """Fast explorer (human or robot) that uses the AMRoNet."""


class State:
    """Behavioural state of a robot (paper sections 4.1-4.2); plain ``int`` codes like :class:`Role`."""

    BASE = 0
    """A base station's reference node."""
    EXPLORE = 1
    """Router random-walking in search of the point where it would lose its last reference."""
    REFERENCE = 2
    """Router that stopped (greedy deployment) and now serves as a reference for others."""
    TRIANGLE = 3
    """Router on its way to a triangular-deployment goal point."""
    TRIANGLE_SETTLED = 4
    """Router that finished its triangular deployment; serves as a reference."""
    AGENT = 5
    """An agent."""
    DROPPED = 6
    """Router an agent has put down that does not relay yet (``agents.drop_settle_s``); then a reference."""
    FAILED = 7
    """Node that failed (``faults``): it stays where it is as an obstacle and neither sends nor relays."""
    RELOCATING = 8
    """Deployed router cut off by a failure, moving to bridge the cut (agent-assisted ``repair: relocate``); it
    relays but serves as no reference until it has settled again."""
    STRIP = 9
    """Router an agent has put down that drives to a goal point of an r-strip lattice (drop rule ``strip-goals``);
    it relays but serves as no reference until it has settled."""


STATE_NAMES: tuple[str, ...] = ("base", "explore", "reference", "triangle", "triangle-settled", "agent", "dropped",
                                 "failed", "relocating", "strip")
ROLE_NAMES: tuple[str, ...] = ("base", "router", "agent")

DEPLOYED_STATES: tuple[int, ...] = (State.BASE, State.REFERENCE, State.TRIANGLE_SETTLED)
"""States of nodes that stay put and act as references for routers and agents."""
MOBILE_STATES: tuple[int, ...] = (State.EXPLORE, State.TRIANGLE, State.AGENT, State.RELOCATING, State.STRIP)
"""States of robots that move in a step."""
SETTLING_STATES: tuple[int, ...] = (State.EXPLORE, State.TRIANGLE)
"""States of routers that have not settled yet."""


@functools.cache
def state_lookup(states: tuple[int, ...]) -> np.ndarray:
    """Boolean table indexed by state code: ``state_lookup(states)[state]`` is a fast ``np.isin``."""
    table = np.zeros(len(STATE_NAMES), dtype=bool)
    table[list(states)] = True
    table.flags.writeable = False
    return table


@njit(cache=True)
def _relaying(role, state, silent, agent):  # pragma: no cover - numba
    """``role != agent and not silent[state]`` robot by robot (one call instead of four array operations)."""
    out = np.empty(role.shape[0], dtype=np.bool_)
    for i in range(role.shape[0]):
        out[i] = role[i] != agent and not silent[state[i]]
    return out


@dataclass
class Swarm:
    """State of every robot of a run, one row per robot.

    Attributes:
        xy: Positions in metres, ``(N, 2)`` float.
        heading: Headings in radians, ``(N,)`` float.
        role: :class:`Role` codes, ``(N,)`` int8.
        state: :class:`State` codes, ``(N,)`` int8.
        status: Base-station id a node belongs to, -1 for none yet, ``(N,)`` int32.
        radius: Footprint radius per robot, ``(N,)`` float.
        max_speed: Maximum speed per robot, ``(N,)`` float.
        model: Index into :attr:`models` per robot, ``(N,)`` int8 (selects the sensor ring).
        models: The distinct robot models present (``model`` indexes them).
        distance: Distance travelled so far per robot in metres, ``(N,)`` float.
    """

    xy: np.ndarray
    heading: np.ndarray
    role: np.ndarray
    state: np.ndarray
    status: np.ndarray
    radius: np.ndarray
    max_speed: np.ndarray
    model: np.ndarray
    models: tuple[RobotModel, ...]
    distance: np.ndarray

    @classmethod
    def build(cls, groups: list[tuple[RobotModel, Role, State, np.ndarray, np.ndarray]]) -> Swarm:
        """Assemble a swarm from groups of robots.

        Args:
            groups: ``(robot_model, role, state, xy, status)`` per group; ``xy`` is ``(n, 2)`` and ``status``
                ``(n,)``. Robots get ids in the order of the groups.

        Returns:
            The swarm, headings all zero.
        """
        models: list[RobotModel] = []
        parts: dict[str, list[np.ndarray]] = {k: [] for k in ("xy", "role", "state", "status", "model")}
        for robot_model, role, state, xy, status in groups:
            if robot_model not in models:
                models.append(robot_model)
            n = len(xy)
            parts["xy"].append(np.asarray(xy, dtype=float).reshape(n, 2))
            parts["role"].append(np.full(n, role, dtype=np.int8))
            parts["state"].append(np.full(n, state, dtype=np.int8))
            parts["status"].append(np.asarray(status, dtype=np.int32).reshape(n))
            parts["model"].append(np.full(n, models.index(robot_model), dtype=np.int8))
        arrays = {k: np.concatenate(v) if v else np.zeros(0) for k, v in parts.items()}
        n_total = len(arrays["xy"]) if len(arrays["xy"]) else 0
        model_idx = arrays["model"].astype(np.int8)
        radius = np.array([m.radius for m in models])[model_idx] if n_total else np.zeros(0)
        speed = np.array([m.max_speed for m in models])[model_idx] if n_total else np.zeros(0)
        return cls(
            xy=arrays["xy"].reshape(-1, 2),
            heading=np.zeros(n_total),
            role=arrays["role"].astype(np.int8),
            state=arrays["state"].astype(np.int8),
            status=arrays["status"].astype(np.int32),
            radius=radius,
            max_speed=speed,
            model=model_idx,
            models=tuple(models),
            distance=np.zeros(n_total),
        )

    _ROW_FIELDS = ("xy", "heading", "role", "state", "status", "radius", "max_speed", "model", "distance")

    @classmethod
    def concat(cls, parts: list[Swarm]) -> Swarm:
        """One swarm holding the robots of ``parts`` one block after another (runs stepped together).

        Raises:
            ValueError: If the parts do not have the same robot models (model codes would mean different robots).
        """
        models = parts[0].models
        if any(p.models != models for p in parts):
            raise ValueError("swarms with different robot models cannot be joined")
        return cls(models=models, **{f: np.concatenate([getattr(p, f) for p in parts]) for f in cls._ROW_FIELDS})

    def rows(self, robots: slice) -> Swarm:
        """The robots ``robots`` (a slice) as a swarm whose arrays are views into this one's."""
        return Swarm(models=self.models, **{f: getattr(self, f)[robots] for f in self._ROW_FIELDS})

    def copy(self) -> Swarm:
        """A swarm with copies of every array."""
        return Swarm(models=self.models, **{f: getattr(self, f).copy() for f in self._ROW_FIELDS})

    def __len__(self) -> int:
        return len(self.xy)

    def extend(self, robot_model: RobotModel, role: int, state: int, xy: np.ndarray, status: np.ndarray,
               heading: np.ndarray | None = None) -> np.ndarray:
        """Add robots (e.g. routers an agent releases) and return their new ids.

        Arrays are reallocated; hold no views of them across a call. Cold: a deployment event, not a step.
        """
        xy = np.asarray(xy, dtype=float).reshape(-1, 2)
        n_new, n_old = len(xy), len(self.xy)
        if robot_model not in self.models:
            self.models = (*self.models, robot_model)
        model = self.models.index(robot_model)
        self.xy = np.vstack([self.xy, xy])
        self.heading = np.concatenate([self.heading, np.zeros(n_new) if heading is None else heading])
        self.role = np.concatenate([self.role, np.full(n_new, role, dtype=np.int8)])
        self.state = np.concatenate([self.state, np.full(n_new, state, dtype=np.int8)])
        self.status = np.concatenate([self.status, np.asarray(status, dtype=np.int32).reshape(n_new)])
        self.radius = np.concatenate([self.radius, np.full(n_new, robot_model.radius)])
        self.max_speed = np.concatenate([self.max_speed, np.full(n_new, robot_model.max_speed)])
        self.model = np.concatenate([self.model, np.full(n_new, model, dtype=np.int8)])
        self.distance = np.concatenate([self.distance, np.zeros(n_new)])
        return np.arange(n_old, n_old + n_new)

    def in_states(self, states: tuple[int, ...]) -> np.ndarray:
        """Boolean mask of robots whose state is one of ``states``."""
        return state_lookup(states)[self.state]

    @property
    def relaying(self) -> np.ndarray:
        """Boolean mask of the nodes that relay: base nodes and routers, less the failed ones and those dropped.

        A router an agent has just put down relays once it has settled (``agents.drop_settle_s``).
        """
        return _relaying(self.role, self.state, state_lookup((State.DROPPED, State.FAILED)), Role.AGENT)

    @property
    def deployed(self) -> np.ndarray:
        """Boolean mask of nodes that serve as references (base nodes and deployed routers)."""
        return self.in_states(DEPLOYED_STATES)
