"""Agent-assisted router deployment (the paper's section 3): agents carry routers and drop them.

An agent drops a router when it is about to lose its last reference. The controller (:mod:`.controller`, the
readable reference, with its parameters :mod:`.params`, releases :mod:`.releases`, the drop rule's view and switches
:mod:`.drop_switches` and the released routers that move :mod:`.movers`), its drop rules (:mod:`.drops`), explorers
(:mod:`.explorers`), repair (:mod:`.relocate`), strip driving (:mod:`.strip_driving`), its fast step (:mod:`.fast`,
:mod:`.stretch`) and kernels (:mod:`.kernels`, :mod:`.stretch_kernels`). Importing the package only declares the
algorithm (:mod:`amronet.algorithms.declaration`, no kernels).
"""

from amronet.algorithms.agent_assisted.params import SCENARIO_DEFAULTS, AgentAssistedParams
from amronet.algorithms.declaration import declare

__all__ = ["AgentAssistedParams"]

declare("agent-assisted", controller="amronet.algorithms.agent_assisted.controller", params=AgentAssistedParams,
        scenario_defaults=SCENARIO_DEFAULTS, follows_paths=True)
