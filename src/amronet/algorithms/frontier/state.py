"""Layout of the frontier explorer's per-agent state and of its navigation kernel's settings.

The explorer keeps one integer row per agent (columns ``_GOAL`` ...) that the navigation kernel reads and
updates in place; the kernel takes its settings as one integer (``_I_*``) and one real (``_F_*``) array.
"""

__all__ = ["REPLAN_REASONS", "STUCK_RADIUS"]

STUCK_RADIUS = 0.5
"""An agent that stayed within this many metres of one point for ``stuck_after`` seconds is stuck."""

# why an agent last replanned (FrontierExplorer.reason)
_NO_GOAL, _REACHED, _NOT_TARGET, _COVERAGE, _STUCK, _PERIODIC, _BLOCKED, _APPROACHED = 1, 2, 3, 4, 5, 6, 7, 8
REPLAN_REASONS = ("", "no goal", "reached", "not a target", "node deployed", "stuck", "periodic", "blocked",
                  "approached")
"""Names of the codes in :attr:`~amronet.algorithms.frontier.FrontierExplorer.reason`."""

# columns of the per-agent integer state
_GOAL, _KIND, _PLEN, _PPOS, _LAST_PLAN, _LAST_MOVE, _REASON, _SOFT, _APPR, _APPR_UNTIL = range(10)
_N_STATE = 10
# integer and real settings of the navigation kernel
_I_WINDOW, _I_ESCAPE, _I_REPLAN, _I_STUCK, _I_LOOK, _I_APPROACH = range(6)
_F_OX, _F_OY, _F_RES, _F_REACH, _F_STUCK_R, _F_CLAIM_R2, _F_REACH_TOL, _F_LANE = range(8)
