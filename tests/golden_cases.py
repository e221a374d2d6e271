"""Fixed-seed runs whose outputs must stay bit for bit what they were (see ``tests/test_golden.py``).

Every case is a scenario, a seed and a short time limit, chosen to exercise every algorithm, explorer, the
batched path and every paper figure. A case's fingerprint is the SHA-256 of ``network.json``, of
``timeseries.csv`` and of ``summary.json`` without its wall-clock fields; a figure's is that of its runs table
without the wall-time column and of its other CSV files.

Regenerate ``tests/golden/outputs.json`` only for a change that is meant to change results, and say so in the
commit: ``python tests/golden_cases.py > tests/golden/outputs.json``.
"""

from __future__ import annotations

import csv
import hashlib
import io
import json
import sys
import tempfile
from pathlib import Path

RUNS = {
    "self-spreading-6x6": ("self-spreading-6x6", 3, {"sim.time_limit": 60}),
    "self-spreading-obstacles-global": ("self-spreading-obstacles-6x6", 5,
                                        {"sim.time_limit": 60, "algorithm.params.triangular": "global"}),
    "self-spreading-autolab": ("self-spreading-autolab", 1, {"sim.time_limit": 30}),
    "self-spreading-office-2bs": ("self-spreading-office", 2, {"sim.time_limit": 30}),
    "agent-assisted-random": ("agent-assisted-office", 1, {"sim.time_limit": 150,
                                                          "algorithm.params.explorer": "random"}),
    "agent-assisted-frontier-4bs": ("agent-assisted-office-4bs", 2,
                                    {"sim.time_limit": 30, "algorithm.params.explorer": "frontier"}),
    "agent-assisted-carried": ("agent-assisted-office", 4, {"sim.time_limit": 60, "agents.routers_carried": 3,
                                                          "algorithm.params.explorer": "frontier"}),
    "dssa-obstacles": ("dssa-obstacles-6x6", 1, {"sim.time_limit": 30}),
    "dssa-open": ("dssa-6x6", 2, {"sim.time_limit": 20}),
    "potential-field-obstacles": ("potential-field-obstacles-6x6", 1, {"sim.time_limit": 30}),
}
"""Single runs: name → (preset, seed, overrides)."""

BATCHES = {
    "batch-self-spreading-obstacles": ("self-spreading-obstacles-6x6", (1, 2, 3), {"sim.time_limit": 40}),
    "batch-potential-field": ("potential-field-6x6", (4, 5, 6), {"sim.time_limit": 20}),
}
"""Batched runs (``amronet.sim.batch.run_seeds``): name → (preset, seeds, overrides)."""

FIGURES = ("fig5", "fig7", "fig10", "fig11")
"""Paper figures, run with ``--quick``."""

_WALL_FIELDS = ("wall_time_s",)


def _sha(data: bytes) -> str:
    return hashlib.sha256(data).hexdigest()


def _drop_default_radio_fields(summary: dict) -> None:
    """Leave out the scenario's radio fields that are at their defaults, but for ``model`` and ``r_c``.

    The radio's link budget (issue #14) added fields to every scenario; left at their defaults they change nothing
    a unit-disk run computes, and leaving them out of the digest keeps it what it was before they existed.
    """
    from amronet.scenario import RadioSpec

    radio = summary.get("scenario", {}).get("radio", {})
    defaults = RadioSpec().model_dump(mode="json")
    for key in list(radio):
        if key not in ("model", "r_c") and radio[key] == defaults.get(key):
            del radio[key]


_KEPT_AGENTS_FIELDS = ("per_base", "robot", "routers_carried")
"""The scenario's ``agents`` fields that were there when the fingerprints were taken: always in the digest."""


def _drop_default_agents_fields(summary: dict) -> None:
    """Leave out the scenario's agents fields that are at their defaults, but for the original three.

    Fields added to ``agents`` since the fingerprints were taken (drop rules and the like) are in every scenario;
    left at their defaults they change nothing the runs compute, and leaving them out of the digest keeps it what
    it was before they existed. Written against :class:`amronet.scenario.AgentsSpec`'s defaults, so a field added
    later is covered too.
    """
    from amronet.scenario import AgentsSpec

    agents = summary.get("scenario", {}).get("agents", {})
    defaults = AgentsSpec().model_dump(mode="json")
    for key in list(agents):
        if key not in _KEPT_AGENTS_FIELDS and key in defaults and agents[key] == defaults[key]:
            del agents[key]


def _drop_no_faults(summary: dict) -> None:
    """Leave out the scenario's ``faults`` list when it is empty (issue #16 added it; empty, it changes nothing)."""
    scenario = summary.get("scenario", {})
    if scenario.get("faults") == []:
        del scenario["faults"]


def _drop_mission(summary: dict) -> None:
    """Leave out the summary's ``mission`` section.

    Issue #19 added it (the agents' outages, relays used, distance travelled) after the fingerprints were taken;
    it is derived from the same run and changes none of the keys that were there, whose digest stays what it was.
    """
    summary.pop("mission", None)


def _drop_pinned_random_explorer(summary: dict) -> None:
    """Leave out ``algorithm.params.explorer`` when it is ``random``.

    ``random`` was the agents' default explorer when the fingerprints were taken, and the case that ran with it
    left the field out; the default is ``frontier`` now, so that case names ``random`` (the same run) and the
    digest leaves the name out, as it was.
    """
    params = summary.get("scenario", {}).get("algorithm", {}).get("params", {})
    if params.get("explorer") == "random":
        del params["explorer"]


def result_fingerprint(result) -> dict[str, str]:
    """Digests of a run's ``network.json``, ``timeseries.csv`` and ``summary.json`` (less wall-clock fields).

    The summary's digest leaves out what was added later without changing results: radio and agents fields at
    their defaults, the ``mission`` section, and the explorer pinned to ``random`` (once the default).
    """
    files = result.files()
    summary = {k: v for k, v in json.loads(files["summary.json"]).items() if k not in _WALL_FIELDS}
    _drop_default_radio_fields(summary)
    _drop_default_agents_fields(summary)
    _drop_mission(summary)
    _drop_no_faults(summary)
    _drop_pinned_random_explorer(summary)
    return {"network.json": _sha(files["network.json"]), "timeseries.csv": _sha(files["timeseries.csv"]),
            "summary": _sha(json.dumps(summary, sort_keys=True).encode()),
            "coverage": f"{summary['coverage']:.6f}", "nodes_total": str(summary["nodes_total"])}


def run_case(name: str) -> dict[str, str]:
    """The fingerprint of single-run case ``name``."""
    import amronet

    preset, seed, overrides = RUNS[name]
    return result_fingerprint(amronet.run(amronet.load_scenario(preset, overrides=overrides), seed=seed))


def batch_case(name: str) -> list[dict[str, str]]:
    """The fingerprints of batched case ``name``, in seed order."""
    import amronet
    from amronet.sim.batch import run_seeds

    preset, seeds, overrides = BATCHES[name]
    return [result_fingerprint(r) for r in run_seeds(amronet.load_scenario(preset, overrides=overrides),
                                                      list(seeds))]


LATER_ALGORITHMS = ("vor", "minimax", "lloyd")
"""Algorithms added to Figs. 10 and 11 after the fingerprints were taken (the Voronoi baselines): their rows are left
out of a figure's digest, which then checks that the paper's algorithms' rows stay what they were."""


def _csv_without_wall_time(text: str) -> bytes:
    rows = list(csv.reader(io.StringIO(text)))
    if rows and "algorithm" in rows[0]:  # written by csv.writer(lineterminator="\n"), as below: the same bytes
        col = rows[0].index("algorithm")
        rows = rows[:1] + [r for r in rows[1:] if r[col] not in LATER_ALGORITHMS]
    if not rows or "wall_time_s" not in rows[0]:
        if not rows or "algorithm" not in rows[0]:
            return text.encode()
        buf = io.StringIO()
        csv.writer(buf, lineterminator="\n").writerows(rows)
        return buf.getvalue().encode()
    drop = rows[0].index("wall_time_s")
    buf = io.StringIO()
    csv.writer(buf, lineterminator="\n").writerows([r[:drop] + r[drop + 1:] for r in rows])
    return buf.getvalue().encode()


def figure_case(name: str) -> dict[str, str]:
    """Digests of the CSV files ``amronet reproduce NAME --quick`` writes (runs tables less wall time)."""
    from amronet.experiments.registry import FIGURES as KNOWN

    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / name
        if name == "fig11":  # fig11 compares with a fig10 of the same runs in a sibling folder
            KNOWN["fig10"].run(Path(tmp) / "fig10", quick=True, workers=1, show_progress=False)
        KNOWN[name].run(out, quick=True, workers=1, show_progress=False)
        return {p.name: _sha(_csv_without_wall_time(p.read_text())) for p in sorted(out.glob("*.csv"))}


def all_cases() -> dict[str, object]:
    """Every case's fingerprint (the content of ``tests/golden/outputs.json``)."""
    return {"runs": {name: run_case(name) for name in RUNS},
            "batches": {name: batch_case(name) for name in BATCHES},
            "figures": {name: figure_case(name) for name in FIGURES}}


if __name__ == "__main__":
    json.dump(all_cases(), sys.stdout, indent=1, sort_keys=True)
    sys.stdout.write("\n")
