"""The plan's files: ``plan.json``, ``plan.md`` and ``typical.png``, the picture of a typical run."""

from __future__ import annotations

import json
from pathlib import Path

from amronet.errors import AmronetError
from amronet.outputs.files import write_files_atomically
from amronet.planning.report import Plan
from amronet.scenario import load_scenario
from amronet.sim import Simulation

__all__ = ["typical_picture", "write_plan"]


def typical_picture(p: Plan) -> bytes | None:
    """PNG of the typical run (re-run here from its seed; the same seed gives the same deployment)."""
    if p.typical_seed is None:
        return None
    result = Simulation(load_scenario(p.scenario), p.typical_seed).run()
    stored = next(r["routers_deployed"] for r in p.runs if r["seed"] == p.typical_seed)
    if result.summary["routers_deployed"] != stored:  # the same seed must give the same run
        raise AmronetError(f"plan: seed {p.typical_seed} re-ran with {result.summary['routers_deployed']} routers, "
                           f"the store holds {stored}; the store was written by another amronet version")
    from amronet.viz.run_snapshot import run_snapshot_png  # matplotlib: imported only when a picture is drawn

    return run_snapshot_png(result)


def write_plan(p: Plan, out_dir: str | Path, keep: tuple[str, ...] = ()) -> Path:
    """Write ``plan.json``, ``plan.md`` and ``typical.png`` into ``out_dir`` (replaced atomically).

    Args:
        p: The plan.
        out_dir: The folder (see :func:`amronet.outputs.files.write_files_atomically`).
        keep: Files of the folder to keep (a result store that lies in it).
    """
    picture = typical_picture(p)
    files = {"plan.json": (json.dumps(p.to_dict(), indent=2) + "\n").encode(),
             "plan.md": p.markdown("typical.png" if picture else None).encode()}
    if picture is not None:
        files["typical.png"] = picture
    return write_files_atomically(Path(out_dir), files, keep=keep)
