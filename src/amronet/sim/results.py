"""The result of a run and its files: ``summary.json``, ``timeseries.csv``, ``network.json``, ``snapshot.png``.

Files are written atomically as a set, and never over files amronet did not write
(:mod:`amronet.outputs.files`): an interrupted or failed run leaves either the previous output or the complete new
one, never half-written files. The picture ``snapshot.png`` is drawn by the caller
(:mod:`amronet.viz.run_snapshot`) and handed in as bytes: results know nothing of pictures.
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from amronet.engine.network import connected_to
from amronet.engine.robots import ROLE_NAMES, STATE_NAMES, Role, State
from amronet.outputs.files import write_files_atomically
from amronet.version import __version__

if TYPE_CHECKING:
    from amronet.outputs.recording import Recorder
    from amronet.sim.run import Metrics, Run

__all__ = ["RunResult"]

TIMESERIES_COLUMNS = ("t", "coverage", "connected_coverage", "routers_deployed", "components")


@dataclass
class RunResult:
    """Everything a run produced.

    Attributes:
        summary: The ``summary.json`` content.
        timeseries: Column name → array, one entry per recorded step (``timeseries.csv``).
        network: The ``network.json`` content: ``r_c``, ``map`` and ``nodes``.
        run: The finished run's books (world, swarm, neighbour table) for pictures and further analysis.
        recorder: The :class:`~amronet.outputs.recording.Recorder` the run was given, if any: agents' trails for the
            snapshot and, when it keeps whole frames, ``recording.npz``.
    """

    summary: dict[str, Any]
    timeseries: dict[str, np.ndarray]
    network: dict[str, Any]
    run: Run
    recorder: Recorder | None = None

    @classmethod
    def from_run(cls, sim: Run, final: Metrics, wall_time_s: float, recorder: Recorder | None = None) -> RunResult:
        """Collect the result of a finished run."""
        sc, sw = sim.scenario, sim.swarm
        routers = sw.role == Role.ROUTER
        deployed_routers = int(np.count_nonzero(sw.deployed & routers))
        report = sim.report()
        summary = {
            "algorithm": sc.algorithm.name,
            "map": sim.world.omap.name,
            "seed": sim.seed,
            "r_c": sc.radio.r_c,
            "sim_time_s": round(sim.t, 9),
            "steps": sim.steps,
            "terminated": sim.terminated,
            "truncated": not sim.terminated,
            "stop_reason": sim.stop_reason,
            "routers_total": int(np.count_nonzero(routers)),
            "routers_deployed": deployed_routers,
            "nodes_total": deployed_routers + len(sim.bases),
            "coverage": final.coverage,
            "connected_coverage": final.connected_coverage,
            "coverage_method": sc.sim.coverage_method,
            "components": final.components,
            "agents": int(len(sim.agents)),
            "agents_connected_fraction": sim.agents_connected_fraction,
            "agents_connected_min": sim.agents_connected_min if len(sim.agents) else None,
            "coverage_target": sim.coverage_target,
            "reachable_area_m2": sim.world.coverage.area_m2,
            "mean_distance_per_router_m": float(sw.distance[routers].mean()) if routers.any() else 0.0,
            "states": sim.state_counts(),
            "settled_at_s": None if sim.settled_at is None else round(sim.settled_at, 9),
            "routers_connected_fraction": _routers_connected(sim),
            "mission": _mission(sim, final, sim.mission_report(), deployed_routers),
            **({"faults": sim.fault_book.summary(sim, sim.faults)} if sim.fault_book is not None else {}),
            **report,
            "wall_time_s": wall_time_s,
            "amronet_version": __version__,
            "scenario": sc.to_dict(),
        }
        columns = TIMESERIES_COLUMNS + (("agents_connected",) if len(sim.agents) else ())
        rows = np.array(sim.rows, dtype=float).reshape(-1, len(columns))
        timeseries = {name: rows[:, k] for k, name in enumerate(columns)}
        for name in ("routers_deployed", "components"):
            timeseries[name] = timeseries[name].astype(np.int64)
        nodes = [
            {
                "id": i,
                "kind": ROLE_NAMES[sw.role[i]],
                "state": STATE_NAMES[sw.state[i]],
                "status": int(sw.status[i]),
                "x": float(sw.xy[i, 0]),
                "y": float(sw.xy[i, 1]),
            }
            for i in range(len(sw))
        ]
        network = {"r_c": sc.radio.r_c, "map": sim.world.omap.name, "nodes": nodes}
        return cls(summary=summary, timeseries=timeseries, network=network, run=sim, recorder=recorder)

    # -- rendering -------------------------------------------------------------------------------------------
    def timeseries_csv(self) -> str:
        """The time series as CSV text."""
        ts = self.timeseries
        agents = "agents_connected" in ts
        lines = [",".join(TIMESERIES_COLUMNS + (("agents_connected",) if agents else ()))]
        for k in range(len(ts["t"])):
            line = (f"{ts['t'][k]:.6g},{ts['coverage'][k]:.6f},{ts['connected_coverage'][k]:.6f},"
                    f"{int(ts['routers_deployed'][k])},{int(ts['components'][k])}")
            lines.append(line + (f",{ts['agents_connected'][k]:.6f}" if agents else ""))
        return "\n".join(lines) + "\n"

    def files(self, snapshot: bytes | None = None) -> dict[str, bytes]:
        """Name → content of every output file.

        Args:
            snapshot: The deployment picture as PNG bytes, written as ``snapshot.png``
                (:func:`amronet.viz.run_snapshot.run_snapshot_png` draws it); ``None``: no picture.
        """
        out = {
            "summary.json": (json.dumps(self.summary, indent=2) + "\n").encode(),
            "timeseries.csv": self.timeseries_csv().encode(),
            "network.json": (json.dumps(self.network, indent=1) + "\n").encode(),
        }
        if snapshot is not None:
            out["snapshot.png"] = snapshot
        if self.recorder is not None and self.recorder.full:
            out["recording.npz"] = self.recorder.npz_bytes(self.run)
        return out

    def save(self, out_dir: str | Path, snapshot: bytes | None = None) -> Path:
        """Write the output files into ``out_dir`` atomically (see the module docstring).

        Args:
            out_dir: The run's folder.
            snapshot: The deployment picture's PNG bytes (see :meth:`files`); ``None``: no ``snapshot.png``.
        """
        return write_files_atomically(Path(out_dir), self.files(snapshot=snapshot))


def _routers_connected(sim: Run) -> float:
    """Fraction of the routers that have a multi-hop path to a base station through the network.

    Failed routers are left out (``faults`` counts them).
    """
    sw = sim.swarm
    routers = (sw.role == Role.ROUTER) & (sw.state != State.FAILED)
    if not routers.any():
        return 1.0
    linked = connected_to(sim.table, sim.live_bases, sim.relay_mask)
    return float(np.count_nonzero(linked & routers) / np.count_nonzero(routers))


def _mission(sim: Run, final: Metrics, report: dict[str, Any], deployed_routers: int) -> dict[str, Any] | None:
    """The summary's ``mission`` section: how well the agents stayed connected and what it cost.

    Args:
        sim: The finished run.
        final: Its final metrics.
        report: The controller's mission report for the run (``Controller.mission_report``): ``relays_used`` and
            ``released_per_agent`` are used when there, its other keys (the drop rule, what it counted) are copied.
        deployed_routers: Routers deployed at the end (``relays_used`` when the report has no such key).

    Returns:
        ``None`` for a run without agents; else ``connected_fraction`` (= ``agents_connected_fraction``),
        ``longest_outage_s`` (over agents), ``outages`` (total), ``time_all_connected_fraction``, ``relays_used``,
        ``relays_per_100m2_covered`` (``None`` when nothing is covered), ``distance_travelled_m`` (total over
        agents) and ``per_agent``: per agent in id order ``id`` (its node id in ``network.json``),
        ``connected_fraction``, ``longest_outage_s``, ``outages``, ``distance_m`` and, when the report has
        ``released_per_agent``, ``relays_dropped``.
    """
    links = sim.agent_links
    if links is None:
        return None
    dt = sim.dt
    fractions = links.connected_fraction
    outages = links.outages
    longest = links.longest_outage_steps
    distance = sim.swarm.distance[sim.agents]
    released = report.get("released_per_agent")
    relays_used = int(report["relays_used"]) if "relays_used" in report else deployed_routers
    covered_m2 = final.coverage * sim.world.coverage.area_m2
    per_agent = []
    for k, node in enumerate(sim.agents):
        entry: dict[str, Any] = {"id": int(node), "connected_fraction": float(fractions[k]),
                                 "longest_outage_s": round(int(longest[k]) * dt, 9), "outages": int(outages[k]),
                                 "distance_m": float(distance[k])}
        if released is not None:
            entry["relays_dropped"] = int(released[k])
        per_agent.append(entry)
    return {
        "connected_fraction": sim.agents_connected_fraction,
        "longest_outage_s": round(int(longest.max()) * dt, 9),
        "outages": int(outages.sum()),
        "time_all_connected_fraction": float(links.all_connected_fraction),
        "relays_used": relays_used,
        "relays_per_100m2_covered": float(relays_used / (covered_m2 / 100)) if covered_m2 > 0 else None,
        "distance_travelled_m": float(distance.sum()),
        **{k: v for k, v in report.items() if k not in ("relays_used", "released_per_agent")},
        "per_agent": per_agent,
    }
