"""The picture subcommands: ``amronet snapshot``, ``amronet animate`` and ``amronet replay``, and ``run --record``.

``amronet run ... --record [--record-every K]`` adds ``recording.npz`` to the run folder (every K-th step,
default the scenario's ``sim.record_every``). Then:

- ``amronet snapshot RUN --out pic.svg [--time T] [--layer signal]``: the deployment picture of one frame
  (default the last), PNG or SVG, from the recording, or from ``network.json`` of a run recorded without
  ``--record``; ``--layer signal`` shades the best RSSI of the routers and base nodes per cell (dBm, the run's
  radio rebuilt from its seed) instead of the uncovered cells;
- ``amronet animate RUN --out run.gif [--layer signal]`` (or ``.mp4`` with ``imageio-ffmpeg`` installed);
- ``amronet replay RUN --out replay.html [--layer signal]``: one self-contained page that plays the run in any
  browser; with ``--layer signal`` it also carries each frame's signal map and toggles between it and the
  uncovered area.

Every output is written atomically. Bad input raises :class:`amronet.errors.AmronetError` with one line naming
the option and the fix.
"""

from __future__ import annotations

import argparse
import json
import math
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING, Any

from amronet.errors import AmronetError

if TYPE_CHECKING:
    from matplotlib.figure import Figure

    from amronet.outputs.recording import Recorder, Recording
    from amronet.scenario import Scenario

__all__ = ["add_parsers", "make_recorder"]


def make_recorder(args: argparse.Namespace, scenario: Scenario) -> Recorder:
    """The recorder of ``amronet run``: whole frames with ``--record`` (or ``--record-every``), else trails only.

    Raises:
        AmronetError: ``--record-every`` is not a positive whole number.
    """
    from amronet.outputs.recording import Recorder

    every = args.record_every if args.record_every is not None else scenario.sim.record_every
    if every < 1:
        raise AmronetError(f"--record-every: {every} must be a whole number of steps >= 1, e.g. 10")
    return Recorder(every=every, full=bool(args.record or args.record_every is not None))


def _run_folder(text: str) -> Path:
    folder = Path(text)
    if not folder.is_dir():
        raise AmronetError(f"RUN: {text!r} is not a folder; give the --out folder of amronet run")
    return folder


def _check_dpi(dpi: float) -> None:
    if not (math.isfinite(dpi) and 10 <= dpi <= 1200):
        raise AmronetError(f"--dpi: {dpi:g} must be a number between 10 and 1200, e.g. 120")


def _frame_index(times: Any, time: float | None) -> int:
    """Index of the last frame at or before ``time`` (the last frame when ``time`` is None)."""
    import numpy as np

    if time is None:
        return len(times) - 1
    if not math.isfinite(time) or time < 0:
        raise AmronetError(f"--time: {time} must be a finite number of seconds >= 0")
    return max(int(np.searchsorted(times, time + 1e-9, side="right")) - 1, 0)


def _damaged(path: Path, why: str) -> AmronetError:
    return AmronetError(f"{path} is damaged or was not written by amronet run ({why}); run it again")


def _read_json_object(path: Path) -> dict[str, Any]:
    """A JSON file of a run folder that must hold an object; one-line errors naming the file."""
    try:
        data = json.loads(path.read_text())
    except json.JSONDecodeError as exc:
        raise _damaged(path, f"not valid JSON: {exc.msg} at line {exc.lineno}") from None
    except UnicodeDecodeError:
        raise _damaged(path, "not UTF-8 text") from None
    except OSError as exc:
        raise AmronetError(f"{path}: cannot read it ({exc.strerror or exc})") from None
    if not isinstance(data, dict):
        raise _damaged(path, f"a JSON {type(data).__name__}, not an object")
    return data


def _snapshot_from_network(folder: Path, dpi: float, layer: str = "coverage") -> Figure:
    """The final snapshot of a run folder without a recording, from ``network.json`` and the scenario."""
    import numpy as np

    from amronet.scenario import load_scenario
    from amronet.sim.assemble import build_medium, build_world
    from amronet.viz import Nodes, Shading, snapshot_figure
    from amronet.viz.signal import SPAN_DB

    if not (folder / "summary.json").is_file() or not (folder / "network.json").is_file():
        raise AmronetError(f"{folder} has neither recording.npz nor network.json and summary.json: give the "
                           "--out folder of amronet run")
    summary = _read_json_object(folder / "summary.json")
    network = _read_json_object(folder / "network.json")
    if "scenario" not in summary:
        raise _damaged(folder / "summary.json", "no 'scenario'")
    try:
        sc = load_scenario(summary["scenario"])
        world = build_world(sc)
    except (AmronetError, KeyError) as exc:
        raise AmronetError(f"{folder}: cannot rebuild the run's map ({exc}); run it again with --record") from None
    if "nodes" not in network or "r_c" not in network:
        raise _damaged(folder / "network.json", f"no {'nodes' if 'nodes' not in network else 'r_c'!r}")
    if not isinstance(network["nodes"], list):
        raise _damaged(folder / "network.json", "'nodes' is not a list")
    try:
        nodes = network["nodes"]
        xy = np.array([[n["x"], n["y"]] for n in nodes], dtype=float).reshape(-1, 2)
        kind = np.array([n["kind"] for n in nodes], dtype=str)
        state = np.array([n["state"] for n in nodes], dtype=str)
        status = np.array([n["status"] for n in nodes], dtype=np.int64)
        r_c = float(network["r_c"])
    except (KeyError, TypeError, ValueError, OverflowError) as exc:
        what = f"no {exc.args[0]!r}" if isinstance(exc, KeyError) else str(exc).splitlines()[0]
        raise _damaged(folder / "network.json", f"a node or r_c is malformed: {what}") from None
    try:
        s = summary
        title = (f"{s['algorithm']} on {s['map']}, seed {s['seed']}: {s['nodes_total']} nodes, "
                 f"coverage {100 * s['coverage']:.1f} %, t = {s['sim_time_s']:g} s")
    except KeyError as exc:
        raise _damaged(folder / "summary.json", f"no {exc.args[0]!r}") from None
    except (TypeError, ValueError) as exc:
        raise _damaged(folder / "summary.json", f"bad value: {exc}") from None
    try:
        medium = build_medium(sc, world.omap, np.random.default_rng(int(summary["seed"])), packet_loss=False)
    except (KeyError, TypeError, ValueError, OverflowError):
        raise _damaged(folder / "summary.json", "no valid 'seed'") from None
    network_xy = xy[kind != "agent"]
    try:
        if not np.isfinite(xy).all():
            raise ValueError("a node's x or y is not a finite number")
        if layer == "signal":
            shading = {"signal": medium.signal_dbm(world.omap, network_xy, floor_db=-SPAN_DB),
                       "threshold_dbm": medium.budget.threshold_dbm}
        else:
            shading = {"covered": medium.covered_mask(world.coverage, network_xy)}
        drawn = Nodes(xy=xy, kind=kind, state=state, status=status, r_c=r_c, links=medium.update(xy).pairs)
        return snapshot_figure(world.omap, drawn, Shading(reachable=world.reachable, **shading), title=title, dpi=dpi)
    except ValueError as exc:  # an unknown kind or state, a negative r_c...
        raise _damaged(folder / "network.json", str(exc).splitlines()[0]) from None


def _check_suffix(text: str, suffixes: tuple[str, ...], shown: str | None = None) -> None:
    """``--out`` must end in one of ``suffixes`` (lower case, with the dot); ``shown``: how the message says it."""
    if Path(text).suffix.lower() not in suffixes:
        raise AmronetError(f"--out: {text!r} must end in {shown or ' or '.join(suffixes)}")


def _write_from_run(args: argparse.Namespace, check: Callable[[Path], None],
                    render: Callable[[Path, Recording | None], Callable[[Path], str]],
                    optional_recording: bool = False) -> int:
    """What ``snapshot``, ``animate`` and ``replay`` share: read the run folder ``args.run``, write ``args.out``.

    In this order: the run folder must be a folder; ``check`` checks ``args.out`` (its suffix) and the command's
    cheap options, before anything is loaded; the run's recording is loaded; ``render(folder, recording)`` draws
    the output and returns ``write(tmp) -> str``, which writes it to a temporary path and says what it wrote; the
    temporary file replaces ``args.out`` atomically, and the line ``WHAT -> OUT`` is printed unless ``args.quiet``.

    Args:
        args: The command's arguments (``run``, ``out``, ``quiet``).
        check: Checks of the output path and the cheap options (raise :class:`AmronetError`).
        render: Draws the output from the run folder and its recording.
        optional_recording: The run need not have a recording (``render`` then gets ``None``); otherwise its
            absence is an error.

    Returns:
        0, the command's exit status.
    """
    from amronet.outputs.files import write_file_atomically
    from amronet.outputs.recording import load_recording

    folder = _run_folder(args.run)
    out = Path(args.out)
    check(out)
    load = not optional_recording or (folder / "recording.npz").is_file()
    write = render(folder, load_recording(folder) if load else None)
    said: list[str] = []
    write_file_atomically(out, lambda tmp: said.append(write(tmp)))
    if not args.quiet:
        print(f"{said[0]} -> {out}")
    return 0


def _cmd_snapshot(args: argparse.Namespace) -> int:
    from amronet.viz.decorations import save_figure
    from amronet.viz.recorded import check_layer, recording_snapshot

    def render(folder: Path, rec: Recording | None) -> Callable[[Path], str]:
        if rec is not None:
            f = _frame_index(rec.t, args.time)
            fig = recording_snapshot(rec, f, dpi=args.dpi, layer=args.layer)
            where = f"frame {f} (t = {rec.t[f]:g} s) of {folder}/recording.npz"
        else:
            if args.time is not None:
                raise AmronetError(f"--time: {folder} has no recording.npz, only the final network: run it again "
                                   "with --record")
            fig = _snapshot_from_network(folder, args.dpi, args.layer)
            where = f"{folder}/network.json"
        fmt = Path(args.out).suffix.lower().lstrip(".")

        def write(tmp: Path) -> str:
            save_figure(fig, tmp, fmt, args.dpi, facecolor="white")
            return where

        return write

    def check(out: Path) -> None:
        _check_dpi(args.dpi)
        _check_suffix(args.out, (".png", ".svg"))
        check_layer(args.layer)

    return _write_from_run(args, check, render, optional_recording=True)


def _cmd_animate(args: argparse.Namespace) -> int:
    from amronet.viz.recorded import check_animation_options, check_layer, write_animation

    def check(out: Path) -> None:
        check_animation_options(out, args.fps, args.every, args.max_frames)
        _check_dpi(args.dpi)
        check_layer(args.layer)

    def render(folder: Path, rec: Recording) -> Callable[[Path], str]:
        def write(tmp: Path) -> str:
            count = write_animation(rec, tmp, fps=args.fps, every=args.every, max_frames=args.max_frames,
                                    dpi=args.dpi, layer=args.layer)
            return f"{count} frames of {rec.frames} recorded, {args.fps:g} per second"

        return write

    return _write_from_run(args, check, render)


def _cmd_replay(args: argparse.Namespace) -> int:
    from amronet.viz.frames import pick_frames
    from amronet.viz.recorded import check_frame_options, check_layer
    from amronet.viz.replay import replay_html

    def render(folder: Path, rec: Recording) -> Callable[[Path], str]:
        page = replay_html(rec, folder, every=args.every, max_frames=args.max_frames, layer=args.layer)
        kept = len(pick_frames(rec.frames, args.every, args.max_frames))

        def write(tmp: Path) -> str:
            tmp.write_bytes(page)
            return (f"replay of {kept} frames of {rec.frames} recorded, {int(rec.n.max())} robots "
                    f"({len(page) / 1e6:.1f} MB)")

        return write

    def check(out: Path) -> None:
        _check_suffix(args.out, (".html", ".htm"), shown=".html")
        check_frame_options(args.every, args.max_frames)
        check_layer(args.layer)

    return _write_from_run(args, check, render)


def add_parsers(sub: argparse._SubParsersAction) -> None:
    """Register ``snapshot``, ``animate`` and ``replay`` on the ``amronet`` subcommand parser."""
    s = sub.add_parser("snapshot", help="draw one frame of a run (PNG or SVG)")
    s.add_argument("run", help="a run folder (amronet run --out)")
    s.add_argument("--out", required=True, help="picture to write (.png or .svg)")
    s.add_argument("--time", type=float, help="simulated time in seconds (default: the end; needs a recording)")
    s.add_argument("--dpi", type=float, default=120)
    s.add_argument("--layer", default="coverage", help="what to shade: coverage (uncovered cells, default) or "
                                                       "signal (best RSSI per cell, dBm)")
    s.add_argument("-q", "--quiet", action="store_true")
    s.set_defaults(func=_cmd_snapshot)

    a = sub.add_parser("animate", help="animate a recorded run (GIF, or MP4 with imageio-ffmpeg)")
    a.add_argument("run", help="a run folder written with amronet run --record")
    a.add_argument("--out", required=True, help="animation to write (.gif or .mp4)")
    a.add_argument("--fps", type=float, default=10.0, help="frames per second (default 10; at most 50 for GIF)")
    a.add_argument("--every", type=int, default=1, help="draw every N-th recorded frame (default 1)")
    a.add_argument("--max-frames", type=int, default=200, help="at most this many frames (default 200)")
    a.add_argument("--dpi", type=float, default=80)
    a.add_argument("--layer", default="coverage", help="what to shade: coverage (default) or signal (best RSSI "
                                                       "per cell; slower)")
    a.add_argument("-q", "--quiet", action="store_true")
    a.set_defaults(func=_cmd_animate)

    r = sub.add_parser("replay", help="write a self-contained HTML page that plays a recorded run")
    r.add_argument("run", help="a run folder written with amronet run --record")
    r.add_argument("--out", required=True, help="page to write (.html)")
    r.add_argument("--every", type=int, default=1, help="keep every N-th recorded frame (default 1)")
    r.add_argument("--max-frames", type=int, default=None, help="at most this many frames (default all)")
    r.add_argument("--layer", default="coverage", help="coverage (default), or signal: the page also carries each "
                                                       "frame's best RSSI per cell and shows it first (larger)")
    r.add_argument("-q", "--quiet", action="store_true")
    r.set_defaults(func=_cmd_replay)
