"""Drop rules of agent-assisted deployment, registered by name in :data:`DROP_RULES` (``algorithm.params.drop_rule``).

A rule decides *when* an agent puts a router down (:mod:`~amronet.algorithms.agent_assisted.drops.base`); the
controller decides
where. Modules, one rule each:

* :mod:`~amronet.algorithms.agent_assisted.drops.last_reference` — ``last-reference``, the paper's greedy rule (the
default);
* :mod:`~amronet.algorithms.agent_assisted.drops.link_quality` — ``link-quality``, location-free (paper section 6;
SPAWAR, NIST);
* :mod:`~amronet.algorithms.agent_assisted.drops.radius` — ``radius``, Robotika's breadcrumb radius (DARPA SubT);
* :mod:`~amronet.algorithms.agent_assisted.drops.junction` — ``distance-junction``, MARBLE's distance, junction and
turn rules;
* :mod:`~amronet.algorithms.agent_assisted.drops.strip_goals` — ``strip-goals``, greedy drops, then each router drives
to an
  r-strip goal point (the paper's section 6);
* :mod:`~amronet.algorithms.agent_assisted.drops.external` — ``external``, the decisions of a policy outside
  (:mod:`amronet.env`).

Importing this package registers them all.
"""

from amronet.algorithms.agent_assisted.drops import (  # noqa: F401 (register)
    external,
    junction,
    last_reference,
    link_quality,
    radius,
    strip_goals,
)
from amronet.algorithms.agent_assisted.drops.base import (
    DROP_RULES,
    AgentView,
    DropContext,
    DropRule,
    validate_drop_params,
)

__all__ = ["DROP_RULES", "AgentView", "DropContext", "DropRule", "validate_drop_params"]
