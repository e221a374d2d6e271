"""``amronet plot``: mean and 95 % confidence interval of one column against another, one line per hue.

Any column of :func:`~amronet.sweeps.tables.run_rows` can be ``x``, ``y`` or ``hue``: an override key
(``radio.r_c``, ``algorithm.name``), a label of the sweep, or a summary field (``nodes_total``, ``coverage``).
Only runs that are done count. A numeric ``x`` is drawn on a numeric axis; anything else as categories.
"""

from __future__ import annotations

import difflib
import math
from pathlib import Path
from typing import Any

import numpy as np

from amronet.errors import AmronetError
from amronet.outputs.files import write_file_atomically
from amronet.sweeps.stats import mean_ci
from amronet.viz.decorations import save_figure

__all__ = ["plot_groups", "save_plot"]


def _is_number(value: Any) -> bool:
    return isinstance(value, int | float) and not isinstance(value, bool)


def _sort_key(value: Any) -> tuple[int, Any]:
    return (0, value) if _is_number(value) else (1, str(value))


def _check_key(option: str, key: str, columns: list[str]) -> None:
    if key in columns:
        return
    close = difflib.get_close_matches(key, columns, n=4)
    hint = f"did you mean {', '.join(close)}?" if close else "columns include " + ", ".join(columns[:12]) + ", ..."
    raise AmronetError(f"{option}: no column {key!r} in the stored runs; {hint}")


def plot_groups(rows: list[dict[str, Any]], x: str, y: str, hue: str | None = None) -> dict[Any, list[dict[str, Any]]]:
    """Group done runs by hue, then x: ``{hue: [{"x", "mean", "ci95", "n"}, ...]}`` (x sorted).

    Raises:
        AmronetError: A key is no column of the runs, ``y`` is not numeric, or no run is done.
    """
    done = [r for r in rows if r.get("status") == "done"]
    if not done:
        raise AmronetError("plot: the store holds no finished run to plot (amronet results lists them)")
    columns = list(dict.fromkeys(k for r in done for k in r))
    for option, key in (("--x", x), ("--y", y), ("--hue", hue)):
        if key is not None:
            _check_key(option, key, columns)
    if not all(_is_number(r.get(y)) or r.get(y) is None for r in done):
        raise AmronetError(f"--y: column {y!r} is not numeric; choose a metric such as nodes_total or coverage")
    groups: dict[Any, dict[Any, list[float]]] = {}
    for r in done:
        if r.get(y) is None:
            continue
        by_x = groups.setdefault(_json_key(r.get(hue)) if hue else None, {})
        by_x.setdefault(_json_key(r.get(x)), []).append(float(r[y]))
    out = {}
    for h in sorted(groups, key=_sort_key):
        points = []
        for xv in sorted(groups[h], key=_sort_key):
            mean, half = mean_ci(np.array(groups[h][xv]))
            points.append({"x": xv, "mean": mean, "ci95": half, "n": len(groups[h][xv])})
        out[h] = points
    return out


def _json_key(value: Any) -> Any:
    return value if value is None or isinstance(value, int | float | str | bool) else str(value)


def save_plot(rows: list[dict[str, Any]], x: str, y: str, out: str | Path, hue: str | None = None,
              title: str | None = None) -> dict[Any, list[dict[str, Any]]]:
    """Draw ``y`` (mean, 95 % CI) against ``x`` per ``hue`` and write it atomically to ``out`` (.png, .svg, .pdf).

    Returns:
        The plotted groups (:func:`plot_groups`).
    """
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure


    out = Path(out)
    if out.suffix.lower() not in (".png", ".svg", ".pdf"):
        raise AmronetError(f"--out: {str(out)!r} must end in .png, .svg or .pdf")
    groups = plot_groups(rows, x, y, hue)
    xs_all = [p["x"] for pts in groups.values() for p in pts]
    numeric = all(_is_number(v) for v in xs_all)
    categories = sorted(set(map(str, xs_all))) if not numeric else []
    fig = Figure(figsize=(6.4, 4.4))
    FigureCanvasAgg(fig)
    ax = fig.add_subplot(1, 1, 1)
    n = len(groups)
    span = (max(xs_all) - min(xs_all)) if numeric and xs_all else 0.0
    for k, (h, pts) in enumerate(groups.items()):
        if numeric:  # lines of several hues side by side, not on top of each other
            xs = np.array([p["x"] for p in pts], dtype=float) + (k - (n - 1) / 2) * 0.01 * (span or 1.0)
        else:
            xs = np.array([categories.index(str(p["x"])) for p in pts], dtype=float) + (k - (n - 1) / 2) * 0.08
        mean = np.array([p["mean"] for p in pts])
        half = np.array([0.0 if math.isnan(p["ci95"]) else p["ci95"] for p in pts])
        label = f"{hue} = {h}" if hue else None
        ax.errorbar(xs, mean, yerr=half, marker="o", capsize=3, label=label)
    if not numeric:
        ax.set_xticks(range(len(categories)), categories, rotation=20 if len(categories) > 4 else 0)
    ax.set_xlabel(x)
    ax.set_ylabel(f"{y} (mean, 95 % CI)")
    ax.set_title(title or f"{y} vs {x}")
    ax.grid(True, alpha=0.3)
    if hue:
        ax.legend(fontsize=8)
    fig.tight_layout()
    fmt = out.suffix.lower().lstrip(".")
    write_file_atomically(out, lambda tmp: save_figure(fig, tmp, fmt, 120))
    return groups
