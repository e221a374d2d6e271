"""``external``: an agent drops a router when a policy outside the controller says so (:mod:`amronet.env`).

Before every step the environment hands over each agent's wish (:meth:`ExternalDrop.command`). The wish means what
the built-in rules' "about to lose my link" means: an agent that wishes and carries a router (and whose last one has
settled) puts one down, next to itself on its reference's side, as under every rule; one that wishes with no router
left turns back toward its reference when tethered (``agents.when_empty: tether``). So a policy that wishes exactly
when the paper's rule (or the link-quality rule) fires deploys exactly what that rule deploys
(:mod:`amronet.env.policies`). A run of a scenario that names this rule without an environment stops at its first
step with one line.
"""

from __future__ import annotations

import numpy as np

from amronet.algorithms.agent_assisted.drops.base import DROP_RULES, AgentView, DropContext, DropRule
from amronet.errors import ScenarioError

__all__ = ["ExternalDrop"]


@DROP_RULES.register("external")
class ExternalDrop(DropRule):
    """Drop when the policy driving the agents (the drop actions of :mod:`amronet.env`) says so."""

    reads_positions = False
    external = True
    """Driven from outside: no warm-up run, no run of its own (:mod:`amronet.env` commands it)."""

    def __init__(self, params: object, context: DropContext) -> None:
        super().__init__(params, context)  # type: ignore[arg-type]
        self._wish: np.ndarray | None = None
        self._t = -np.inf
        self.last_dropped = np.zeros(context.n_agents, dtype=bool)
        """Which agents put a reference router down in the last step (what an agent knows it did)."""

    def command(self, wish: np.ndarray) -> None:
        """The next step's wishes, one per agent (``True``: drop now, or turn back without a router)."""
        self._wish = np.asarray(wish, dtype=bool)

    def _wishes(self, view: AgentView) -> np.ndarray:
        if self._wish is None:
            raise ScenarioError("algorithm.params.drop_rule", "the 'external' drop rule takes its decisions from "
                                "amronet.env (deployment_env); to run a scenario alone choose another rule, e.g. "
                                "last-reference")
        if view.t != self._t:  # a new step: forget what the last one dropped
            self._t = view.t
            self.last_dropped = np.zeros(len(self._wish), dtype=bool)
        return self._wish

    def decide(self, view: AgentView) -> np.ndarray:  # noqa: D102
        return self._wishes(view) & view.can_drop

    def losing(self, view: AgentView) -> np.ndarray:
        """The wish: a tethered agent with no router left turns back where it would have dropped."""
        return self._wishes(view).copy()

    def dropped(self, who: np.ndarray, view: AgentView) -> None:
        """Remember who put a router down this step."""
        self.last_dropped = np.asarray(who, dtype=bool).copy()
