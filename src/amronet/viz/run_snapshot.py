"""The deployment picture of a finished run (``snapshot.png``), drawn from its :class:`~amronet.sim.results.RunResult`.

A result does not draw itself: whoever writes the run's files asks for the picture here and hands its bytes to
:meth:`~amronet.sim.results.RunResult.save` (``amronet run``, the planner's typical run).
"""

from __future__ import annotations

import io
from typing import TYPE_CHECKING

import numpy as np
from matplotlib.figure import Figure

from amronet.engine.robots import ROLE_NAMES, STATE_NAMES
from amronet.viz.snapshot import Nodes, Shading, snapshot_figure

if TYPE_CHECKING:
    from amronet.sim.results import RunResult

__all__ = ["run_snapshot_figure", "run_snapshot_png"]


def run_snapshot_figure(result: RunResult, dpi: float = 120) -> Figure:
    """The picture of a finished run: its final deployment, coverage shaded, the agents' trails if recorded.

    Args:
        result: The run's result.
        dpi: Resolution.

    Returns:
        The Agg figure (see :func:`~amronet.viz.snapshot.snapshot_figure`).
    """
    sim = result.run
    sw = sim.swarm
    covered = sim.medium.covered_mask(sim.world.coverage, sw.xy[sim.relay_mask])
    s = result.summary
    title = (f"{s['algorithm']} on {s['map']}, seed {s['seed']}: {s['nodes_total']} nodes, "
             f"coverage {100 * s['coverage']:.1f} %, t = {s['sim_time_s']:g} s")
    nodes = Nodes(xy=sw.xy, kind=np.array(ROLE_NAMES)[sw.role], state=np.array(STATE_NAMES)[sw.state],
                  status=sw.status, r_c=sim.scenario.radio.r_c, links=sim.table.pairs,
                  trails=result.recorder.trails() if result.recorder is not None else None)
    return snapshot_figure(sim.world.omap, nodes, Shading(reachable=sim.world.reachable, covered=covered),
                           title=title, dpi=dpi)


def run_snapshot_png(result: RunResult, dpi: int = 120) -> bytes:
    """The picture of a finished run (:func:`run_snapshot_figure`) as PNG bytes: ``snapshot.png``."""
    buf = io.BytesIO()
    run_snapshot_figure(result, dpi).savefig(buf, format="png", dpi=dpi)
    return buf.getvalue()
