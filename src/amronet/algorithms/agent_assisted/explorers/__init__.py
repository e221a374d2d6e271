"""Exploration strategies of the agents, registered by name in :data:`EXPLORERS` (the paper uses ``"random"``).

The default is ``"frontier"`` (:data:`amronet.algorithms.agent_assisted.params.DEFAULT_EXPLORER`): the one that
finishes on real floor plans; the paper's ``"random"`` stays in rooms whose doors are narrower than 1.2 m.

An explorer sets the headings of the agents it is given from their sonar readings; it may keep its own state.
A new one subclasses :class:`Explorer` and registers itself with ``@EXPLORERS.register("name")``
(:mod:`~amronet.algorithms.agent_assisted.explorers.base`); scenarios pick it with ``algorithm.params.explorer``.

Modules: :mod:`~amronet.algorithms.agent_assisted.explorers.base` (the base class and the registry),
:mod:`~amronet.algorithms.agent_assisted.explorers.random_walk` (``"random"``, the paper's, and ``"random-escape"``, a
random walk
that leaves rooms), :mod:`~amronet.algorithms.agent_assisted.explorers.frontier`
(``"frontier"``), :mod:`~amronet.algorithms.agent_assisted.explorers.wall_follow` (``"wall-follow"``) and
:mod:`~amronet.algorithms.agent_assisted.explorers.external` (``"external"``: the motion actions of
:mod:`amronet.env`). Importing
this package
registers them all. :mod:`~amronet.algorithms.agent_assisted.explorers.trajectory` (:class:`PathFollower`) is not
registered: it
steers agents along the paths a scenario gives (``agents.trajectories``) and falls back to the chosen explorer.
"""

from amronet.algorithms.agent_assisted.explorers.base import EXPLORERS, Explorer
from amronet.algorithms.agent_assisted.explorers.external import ExternalExplorer
from amronet.algorithms.agent_assisted.explorers.frontier import FrontierExplorer
from amronet.algorithms.agent_assisted.explorers.random_walk import RandomExplorer
from amronet.algorithms.agent_assisted.explorers.trajectory import PathFollower
from amronet.algorithms.agent_assisted.explorers.wall_follow import WallFollowExplorer

__all__ = ["EXPLORERS", "Explorer", "ExternalExplorer", "FrontierExplorer", "PathFollower", "RandomExplorer",
           "WallFollowExplorer"]
