"""What ``amronet run`` prints about a finished run: a few short lines made from its ``summary.json``.

Every run gets the headline, its nodes and its coverage. A run with agents adds how long they were connected, their
outages and the relays they used (the summary's ``mission``); a run with faults adds each fault event (when, what
failed, whether and when every survivor had a path to a base station again) and what the repair cost (the
summary's ``faults``). Lines after the headline are indented and start with a label in a column of their own.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

__all__ = ["folder_name", "run_lines", "wrote_line"]

_LABEL = 10
"""Width of the label column."""
_EVENTS_SHOWN = 4
"""Fault events listed one per line; beyond, the rest are summed up in one line."""


def _line(label: str, text: str) -> str:
    return f"  {label:<{_LABEL}}{text}"


def _plural(n: int, word: str) -> str:
    return f"{n} {word}" if n == 1 else f"{n} {word}s"


def folder_name(out: str | Path) -> str:
    """``out`` as a folder name for messages: ending in exactly one ``/`` (``plan/`` and ``plan`` give ``plan/``)."""
    text = str(Path(out))
    return text if text.endswith("/") else text + "/"


def wrote_line(out: str | Path, files: list[str]) -> str:
    """The closing line of ``amronet run``: the folder and the files written into it."""
    return _line("wrote", f"{folder_name(out)}: {' '.join(files)}")


def run_lines(summary: dict[str, Any]) -> list[str]:
    """The lines ``amronet run`` prints about a run, from its summary (``summary.json``'s content).

    Args:
        summary: The run's summary (:class:`~amronet.sim.results.RunResult`'s ``summary``).

    Returns:
        The headline, ``nodes`` and ``coverage``; with agents (a ``mission`` section) ``agents``, ``outages``
        and ``relays``; with faults (a ``faults`` section) ``faults`` (one line per event) and ``repair``.
    """
    s = summary
    model = s["scenario"]["radio"]["model"]
    radio = "" if model == "unit-disk" else f", {model} radio"
    lines = [f"{s['algorithm']} on {s['map']} (seed {s['seed']}, r_c = {s['r_c']:g} m{radio}): "
             f"{s['stop_reason']} after {s['sim_time_s']:g} s simulated, {s['wall_time_s']:.1f} s wall"]
    bases = s["nodes_total"] - s["routers_deployed"]
    states = ", ".join(f"{name} {count}" for name, count in s["states"].items())
    lines.append(_line("nodes", f"{s['nodes_total']} ({s['routers_deployed']} of {s['routers_total']} routers "
                                f"deployed, {_plural(bases, 'base node')}); states: {states}"))
    lines.append(_line("coverage", f"{100 * s['coverage']:.2f} %, connected {100 * s['connected_coverage']:.2f} % "
                                   f"of {s['reachable_area_m2']:.1f} m² reachable ({s['coverage_method']})"))
    if s.get("mission"):
        lines += _mission_lines(s["mission"])
    if "faults" in s:
        lines += _fault_lines(s["faults"])
    return lines


def _mission_lines(m: dict[str, Any]) -> list[str]:
    """``agents``, ``outages`` and ``relays``: how well the agents stayed connected and what it cost."""
    agents = m.get("per_agent") or []
    connected = f"{len(agents)}: connected {100 * m['connected_fraction']:.1f} % of the time"
    if len(agents) > 1:
        worst = min(a["connected_fraction"] for a in agents)
        connected += (f" on average, worst {100 * worst:.1f} %, all at once "
                      f"{100 * m['time_all_connected_fraction']:.1f} %")
    lines = [_line("agents", connected)]
    outages = m["outages"]
    lines.append(_line("outages", f"{outages}, longest {m['longest_outage_s']:g} s" if outages else "none"))
    per_area = m.get("relays_per_100m2_covered")
    density = "" if per_area is None else f", {per_area:.1f} per 100 m² covered"
    lines.append(_line("relays", f"{m['relays_used']} used{density}"))
    return lines


def _fault_lines(f: dict[str, Any]) -> list[str]:
    """``faults``: one line per event (the first few), and ``repair``: routers moved and added since."""
    events = f.get("events") or []
    if not events:
        lines = [_line("faults", "none struck before the run ended")]
    else:
        shown = events if len(events) <= _EVENTS_SHOWN else events[: _EVENTS_SHOWN - 1]
        lines = [_line("faults" if k == 0 else "", _event_text(ev)) for k, ev in enumerate(shown)]
        rest = events[len(shown):]
        if rest:
            restored = sum(ev["restored_after_s"] is not None for ev in rest)
            nodes = sum(len(ev["nodes"]) for ev in rest)
            lines.append(_line("", f"... {len(rest)} more events until t = {rest[-1]['t']:g} s: "
                                   f"{_plural(nodes, 'node')} failed, {restored} of {len(rest)} restored"))
    lines += [_line("", f"skipped: {text}") for text in f.get("skipped", [])]
    if "routers_moved" in f:
        lines.append(_line("repair", f"{_plural(f['routers_moved'], 'router')} moved "
                                     f"({f['repair_distance_m']:.1f} m in all), "
                                     f"{_plural(f['extra_routers'], 'router')} added after the first fault"))
    return lines


def _event_text(ev: dict[str, Any]) -> str:
    """``t = 300 s: 2 routers failed, connected 13.9 → 7.5 %, restored after 25.5 s``."""
    nodes = ev["nodes"]
    if ev["kind"] == "base_station":
        what = f"base station (node {', '.join(map(str, nodes))}) failed"
    elif ev["kind"] == "ids":
        what = f"{'node' if len(nodes) == 1 else 'nodes'} {', '.join(map(str, nodes))} failed"
    else:
        what = f"{_plural(len(nodes), 'router')} failed"
    restored = ev["restored_after_s"]
    back = "not restored" if restored is None else f"restored after {restored:g} s"
    return (f"t = {ev['t']:g} s: {what}, connected {100 * ev['connected_coverage_before']:.1f} → "
            f"{100 * ev['connected_coverage_after']:.1f} %, {back}")
