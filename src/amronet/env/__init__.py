"""Multi-agent reinforcement-learning environments (PettingZoo) over amronet's simulator; the optional extra ``rl``.

* :func:`deployment_env` -- agent-assisted deployment: the exploring agents choose how to move and when to drop a
  router (:mod:`amronet.env.agents`);
* :func:`router_env` -- self-spreading: the routers choose how to walk and when to settle (:mod:`amronet.env.routers`);
* :mod:`amronet.env.policies` -- the paper's rules as policies of an observation (scripted baselines);
* :mod:`amronet.env.vector` -- many seeds stepped at once, with arrays in and out.

Observations (:mod:`amronet.env.observe`) hold only what a robot senses or hears; actions are in
:mod:`amronet.env.actions`. Importing this package without PettingZoo and Gymnasium raises one line saying how to
install them (``pip install 'amronet[rl]'``); nothing else of amronet needs them.
"""

from amronet.env._extra import require_extra

require_extra()

from amronet.env.agents import DeploymentEnv  # noqa: E402 (after the check of the extra)
from amronet.env.config import EnvConfig, RewardWeights  # noqa: E402
from amronet.env.errors import EnvError, MissingExtraError  # noqa: E402
from amronet.env.make import deployment_env, router_env  # noqa: E402
from amronet.env.routers import RouterEnv  # noqa: E402

__all__ = ["DeploymentEnv", "EnvConfig", "EnvError", "MissingExtraError", "RewardWeights", "RouterEnv",
           "deployment_env", "router_env"]
