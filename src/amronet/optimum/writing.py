"""The optimum's files: ``optimum.json`` and ``optimum.png``, written atomically into an amronet output folder."""

from __future__ import annotations

import json
from pathlib import Path

from amronet.optimum.report import Optimum
from amronet.outputs.files import write_files_atomically

__all__ = ["write_optimum"]


def write_optimum(opt: Optimum, out_dir: str | Path, picture: bool = True) -> Path:
    """Write ``optimum.json`` (and ``optimum.png``) as the whole content of ``out_dir``, with its manifest.

    Raises:
        AmronetError: ``out_dir`` holds files amronet did not write, or cannot be written
            (:func:`~amronet.outputs.files.write_files_atomically`).
    """
    files = {"optimum.json": (json.dumps(opt.to_dict(), indent=2) + "\n").encode()}
    if picture:
        from amronet.optimum.picture import optimum_png  # matplotlib: imported only when a picture is drawn

        files["optimum.png"] = optimum_png(opt)
    return write_files_atomically(Path(out_dir), files)
