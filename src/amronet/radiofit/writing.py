"""The fit's folder: ``fit.json``, ``radio.yaml`` and the pictures, written atomically with amronet's manifest."""

from __future__ import annotations

import json
import re
from pathlib import Path

import yaml

from amronet.outputs.files import write_files_atomically
from amronet.radiofit.fit import RadioFit
from amronet.world.occupancy import OccupancyMap

__all__ = ["FILES", "attribution_beside", "radio_yaml", "write_fit"]

FILES = ("fit.json", "radio.yaml", "fit.png", "residuals-map.png")
"""What the folder holds (and its manifest)."""


def attribution_beside(data_file: str | Path) -> str | None:
    """The ``Attribution:`` paragraph of a ``README.md`` beside ``data_file`` (a data set's licence), if any."""
    readme = Path(data_file).parent / "README.md"
    try:
        text = readme.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError):
        return None
    m = re.search(r"Attribution:\s*(.+?)(?:\n\s*\n|\n\s*[*#-] )", text + "\n\n", re.S)
    return " ".join(m.group(1).split()) if m else None


def radio_yaml(block: dict, label: str, attribution: str | None) -> str:
    """A ``radio:`` block to paste into a scenario, with where it comes from as comments."""
    head = [f"# Fitted by amronet radio-fit ({label}); see fit.json for intervals and cross-validation.",
            "# Only tx_dbm - pl0_db is determined by the data; threshold_dbm is the receivers' floor."]
    if attribution:
        head.append(f"# Data: {attribution}")
    return "\n".join(head) + "\n" + yaml.safe_dump({"radio": block}, sort_keys=False)


def write_fit(rf: RadioFit, doc: dict, omap: OccupancyMap, out_dir: str | Path, pictures: bool = True) -> Path:
    """Write ``fit.json``, ``radio.yaml`` (and the pictures) as the whole content of ``out_dir``.

    Raises:
        AmronetError: ``out_dir`` holds files amronet did not write, or cannot be written.
    """
    files = {"fit.json": (json.dumps(doc, indent=2, allow_nan=True) + "\n").encode(),
             "radio.yaml": radio_yaml(doc["radio"], doc["chosen"], doc["data"].get("attribution")).encode()}
    if pictures:
        from amronet.radiofit.pictures import fit_png, residual_map_png  # matplotlib: only when drawing

        files["fit.png"] = fit_png(rf, rf.best)
        files["residuals-map.png"] = residual_map_png(rf, rf.best, omap)
    return write_files_atomically(Path(out_dir), files)
