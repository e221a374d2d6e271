"""``last-reference``: the paper's greedy rule (section 4.1), measured by distance on the radio's links.

An agent drops a router when it is about to lose its last reference: every reference it hears is at least
``r_eff = (1 - loss_margin) r_c`` away. The router goes down next to the agent, within ``r_c`` of its current
reference, so it is linked to it on the unit disk.
"""

from __future__ import annotations

import numpy as np

from amronet.algorithms.agent_assisted.drops.base import DROP_RULES, AgentView, DropRule

__all__ = ["LastReference"]


@DROP_RULES.register("last-reference")
class LastReference(DropRule):
    """The paper's rule: drop when about to lose the last reference."""

    def decide(self, view: AgentView) -> np.ndarray:  # noqa: D102
        return self.losing(view) & view.can_drop
