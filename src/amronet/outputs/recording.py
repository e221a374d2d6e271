"""Recordings of runs: every k-th step's positions, states and statuses, compact enough for 3 000 robots.

A :class:`Recorder` is the one hook into the simulation: :meth:`Loop.execute <amronet.sim.loop.Loop.execute>`
shows it the simulation in the metrics phase of every step, and it keeps a copy of the swarm's arrays at every
``every``-th step and at the last one (a few array copies per kept frame, no loop over robots). At the end
:meth:`Recorder.npz_bytes` encodes the frames into one ``recording.npz`` (``numpy.savez_compressed``) that the
run writes with its other files, atomically. :class:`Recording` loads it back.

What ``recording.npz`` holds (format ``amronet-recording/1``):

- ``steps`` int32 ``(F,)``, ``t`` float64 ``(F,)``: the step and simulated time of each frame;
- ``n`` int32 ``(F,)``: robots present in each frame (agents may release routers; ids only grow), ``kind`` uint8
  ``(N,)`` (:class:`~amronet.engine.robots.Role` codes of every robot ever present);
- ``xy_delta`` uint16 ``(F, N, 2)``: positions quantized on a grid of ``xy_quantum`` metres from ``xy_origin``
  (the map's lower-left corner; the quantum is the map's longer side / 65 535, about 0.3 mm for the 20 m
  autolab) and stored as differences to the previous frame modulo 2**16, so robots that stand still cost
  nearly nothing after compression; a robot not yet present holds the position at which it appears;
- ``state`` uint8 ``(F, N)`` (:class:`~amronet.engine.robots.State` codes) and ``status`` uint8 ``(F, N)``, where 255
  means "no base station yet" (``int16`` with -1 when there are 255 or more base stations);
- links: with the unit-disk medium they are *not* stored — they are exactly the pairs within ``r_c``, and
  :meth:`Recording.links` recomputes them from the recorded positions (a pair whose distance lies within about
  one quantum of ``r_c`` may come out differently from the run); any other medium stores ``link_pairs``
  ``(L, 2)`` with ``link_offsets`` ``(F + 1,)`` (CSR style);
- the map (``map_cells`` int8, ``map_resolution``, ``map_origin``) and ``reachable`` (bit-packed), so that a
  recording can be drawn without the scenario's files, and ``meta``: a JSON string (algorithm, map name,
  seed, ``r_c``, ``dt``, ``every``, medium, stop reason, and the medium's resolved link budget ``budget`` with
  ``packet_loss``).

Before anything is decoded, every reader goes through :mod:`amronet.outputs.recording_checks`: each array's header
(shape and type) is read alone, the layout and the memory are checked before any data is read, and the values
(finite scales, bounds, codes, counts) before anything is decoded; a damaged or forged file is one line
(:class:`~amronet.errors.RecordingError`) naming the file, the array and what is wrong.

The medium's name, link budget and the seed rebuild the run's radio (:attr:`Recording.medium`, its shadowing field
included): coverage (:meth:`Recording.covered`) and the signal map (:meth:`Recording.signal`) of any frame are the
run's, under walls and shadowing too. Recordings written before ``budget`` was kept are read with the unit disk of
``r_c``, as they were drawn then.
"""

from __future__ import annotations

import dataclasses
import io
import json
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from amronet.engine.coverage import CoverageArea
from amronet.engine.neighbours import neighbour_csr, pairs_from_csr
from amronet.engine.propagation import LinkBudget
from amronet.engine.radio import RadioMedium, make_medium
from amronet.engine.robots import ROLE_NAMES, STATE_NAMES, Role, State, state_lookup
from amronet.errors import AmronetError, RecordingError
from amronet.outputs.recording_checks import read_budget, read_meta, read_recording_arrays, validate
from amronet.outputs.recording_codec import (
    FORMAT,
    Q_MAX,
    backfill,
    decode_positions,
    decode_status,
    encode_positions,
    encode_status,
    pad,
)
from amronet.world.occupancy import OccupancyMap

if TYPE_CHECKING:
    from amronet.sim.run import Run

__all__ = ["FORMAT", "Recorder", "Recording", "decode_positions", "encode_positions", "load_recording"]


class Recorder:
    """Keeps every ``every``-th step of a run (and its last step) for a recording or for agents' trails.

    Args:
        every: Keep the frames of steps ``0, every, 2 every, ...`` and the last step (>= 1).
        full: Keep positions, states and statuses of every robot (for ``recording.npz``); with ``False`` only
            the agents' positions are kept, for the trails in the snapshot.

    Raises:
        AmronetError: ``every`` is not a positive integer.
    """

    def __init__(self, every: int = 10, full: bool = True) -> None:
        if isinstance(every, bool) or not isinstance(every, int | np.integer) or every < 1:
            raise AmronetError(f"--record-every: {every!r} must be a whole number of steps >= 1, e.g. 10")
        self.every = int(every)
        self.full = full
        self.steps: list[int] = []
        self.t: list[float] = []
        self._xy: list[np.ndarray] = []
        self._state: list[np.ndarray] = []
        self._status: list[np.ndarray] = []
        self._pairs: list[np.ndarray] = []
        self._agent_xy: list[np.ndarray] = []
        self._agents: np.ndarray | None = None
        self._store_links: bool | None = None

    def __len__(self) -> int:
        return len(self.steps)

    def observe(self, sim: Run) -> None:
        """Keep this step if it is an ``every``-th step or the run has stopped (called in the metrics phase)."""
        steps = sim.steps
        if self.steps and self.steps[-1] == steps:
            return
        if steps % self.every and sim.stop_reason is None:
            return
        sw = sim.swarm
        self.steps.append(steps)
        self.t.append(sim.t)
        if self._agents is None:
            self._agents = np.asarray(sim.agents, dtype=np.int64)
        self._agent_xy.append(sw.xy[self._agents].copy())
        if not self.full:
            return
        self._xy.append(sw.xy.astype(np.float32))
        self._state.append(sw.state.astype(np.uint8))
        self._status.append(sw.status.astype(np.int32))
        if self._store_links is None:
            self._store_links = sim.scenario.radio.model != "unit-disk"
        if self._store_links:
            self._pairs.append(sim.table.pairs.astype(np.int32))

    def trails(self) -> dict[int, np.ndarray]:
        """Agent id → its path ``(frames, 2)`` over the kept frames (empty without agents)."""
        if not self._agent_xy or self._agents is None or len(self._agents) == 0:
            return {}
        paths = np.stack(self._agent_xy)
        return {int(a): paths[:, k] for k, a in enumerate(self._agents)}

    def arrays(self, sim: Run) -> dict[str, np.ndarray]:
        """The recording's arrays (see the module docstring), encoded, ready for ``np.savez_compressed``.

        Raises:
            AmronetError: The recorder kept no frame or only trails (``full=False``).
        """
        if not self.full or not self._xy:
            raise AmronetError("record: nothing was recorded; run with --record")
        sw, omap = sim.swarm, sim.world.omap
        n = np.array([len(x) for x in self._xy], dtype=np.int32)
        n_all = int(n.max())
        xy = pad(self._xy, n_all, (2,), np.float32)
        state = pad(self._state, n_all, (), np.uint8)
        status = pad(self._status, n_all, (), np.int32)
        backfill(n, xy, state, status)
        origin = np.array([omap.extent[0], omap.extent[2]], dtype=np.float64)
        quantum = max(omap.size_m) / Q_MAX
        sc = sim.scenario
        medium = sim.medium
        meta = {
            "format": FORMAT,
            "algorithm": sc.algorithm.name,
            "scenario": sc.name,
            "map": omap.name,
            "seed": sim.seed,
            "r_c": sc.radio.r_c,
            "medium": sc.radio.model,
            "dt": sim.dt,
            "every": self.every,
            "stop_reason": sim.stop_reason,
            "budget": dataclasses.asdict(medium.budget),
            "packet_loss": bool(medium.packet_loss),
        }
        out = {
            "meta": np.array(json.dumps(meta)),
            "steps": np.array(self.steps, dtype=np.int32),
            "t": np.array(self.t, dtype=np.float64),
            "n": n,
            "kind": sw.role[:n_all].astype(np.uint8),
            "xy_origin": origin,
            "xy_quantum": np.array(quantum),
            "xy_delta": encode_positions(xy, origin, quantum),
            "state": state,
            "status": encode_status(status),
            "map_cells": omap.cells.astype(np.int8),
            "map_resolution": np.array(float(omap.resolution)),
            "map_origin": np.array(omap.origin, dtype=np.float64),
            "reachable": np.packbits(sim.world.reachable, axis=None),
        }
        if self._store_links:
            counts = np.array([len(p) for p in self._pairs], dtype=np.int64)
            offsets = np.zeros(len(counts) + 1, dtype=np.int64)
            np.cumsum(counts, out=offsets[1:])
            pairs = np.concatenate(self._pairs) if offsets[-1] else np.zeros((0, 2), np.int32)
            out["link_offsets"] = offsets
            out["link_pairs"] = pairs.astype(np.uint16 if n_all <= Q_MAX else np.int32)
        return out

    def npz_bytes(self, sim: Run) -> bytes:
        """The content of ``recording.npz``."""
        buf = io.BytesIO()
        np.savez_compressed(buf, **self.arrays(sim))
        return buf.getvalue()


@dataclass
class Recording:
    """A loaded recording (see the module docstring for the file format).

    Attributes:
        meta: Algorithm, map name, seed, ``r_c``, ``dt``, ``every``, medium and stop reason.
        steps: Step of each frame ``(F,)``.
        t: Simulated time of each frame in seconds ``(F,)``.
        n: Robots present in each frame ``(F,)``.
        kind: Role code of every robot ``(N,)``.
        xy: Positions in metres ``(F, N, 2)`` float32.
        state: State codes ``(F, N)`` uint8.
        status: Base-station ids ``(F, N)`` int16, -1 for none yet.
        omap: The run's map.
        reachable: The free cells that count ``omap.shape``.
        xy_delta: The encoded positions, as stored (for the replay page, which decodes them itself).
        xy_origin: Origin of the position grid ``(2,)``.
        xy_quantum: Metres per step of the position grid.
        link_offsets: Stored links' offsets per frame ``(F + 1,)``, or ``None`` when links are recomputed.
        link_pairs: Stored links ``(L, 2)``, or ``None``.
        budget: The run's resolved link budget (``meta["budget"]``), or ``None`` for a recording written before
            it was kept (then the radio is the unit disk of ``r_c``).
    """

    meta: dict[str, Any]
    steps: np.ndarray
    t: np.ndarray
    n: np.ndarray
    kind: np.ndarray
    xy: np.ndarray
    state: np.ndarray
    status: np.ndarray
    omap: OccupancyMap
    reachable: np.ndarray
    xy_delta: np.ndarray
    xy_origin: np.ndarray
    xy_quantum: float
    link_offsets: np.ndarray | None = None
    link_pairs: np.ndarray | None = None
    budget: LinkBudget | None = None
    _coverage: Any = field(default=None, repr=False)
    _medium: Any = field(default=None, repr=False)

    @property
    def frames(self) -> int:
        """Number of frames."""
        return len(self.steps)

    @property
    def r_c(self) -> float:
        """Communication radius in metres."""
        return float(self.meta["r_c"])

    @classmethod
    def from_arrays(cls, data: dict[str, np.ndarray], where: str = "recording") -> Recording:
        """Build a recording from the arrays of ``recording.npz``, checked first (:mod:`~.recording_checks`).

        Raises:
            RecordingError: An array is missing, of another type or shape than the others, holds values out of
                range (non-finite or non-positive scales, unknown codes, counts that disagree), or the meta is
                malformed or of another format than ``amronet-recording/1``.
        """
        meta = read_meta(data, where)
        budget = read_budget(meta, where) if "budget" in meta else None
        validate(data, where)
        try:
            origin = np.asarray(data["xy_origin"], dtype=np.float64)
            quantum = float(data["xy_quantum"])
            delta = np.asarray(data["xy_delta"], dtype=np.uint16)
            cells = np.asarray(data["map_cells"], dtype=np.int8)
            omap = OccupancyMap(str(meta["map"]), float(data["map_resolution"]),
                                tuple(map(float, data["map_origin"])), cells)
            reachable = np.unpackbits(data["reachable"], count=cells.size).astype(bool).reshape(cells.shape)
            return cls(
                meta=meta,
                steps=np.asarray(data["steps"], dtype=np.int64),
                t=np.asarray(data["t"], dtype=np.float64),
                n=np.asarray(data["n"], dtype=np.int64),
                kind=np.asarray(data["kind"], dtype=np.uint8),
                xy=decode_positions(delta, origin, quantum),
                state=np.asarray(data["state"], dtype=np.uint8),
                status=decode_status(np.asarray(data["status"])),
                omap=omap,
                reachable=reachable,
                xy_delta=delta,
                xy_origin=origin,
                xy_quantum=quantum,
                link_offsets=np.asarray(data["link_offsets"], dtype=np.int64) if "link_offsets" in data else None,
                link_pairs=np.asarray(data["link_pairs"], dtype=np.int64) if "link_pairs" in data else None,
                budget=budget,
            )
        except (ValueError, TypeError, IndexError) as exc:  # not expected after the checks: still one line
            raise RecordingError(where, "file", f"{type(exc).__name__} reading its arrays") from None

    # -- one frame -------------------------------------------------------------------------------------------
    def frame(self, f: int) -> dict[str, np.ndarray]:
        """Arrays of frame ``f`` for the robots present: ``xy`` (float64), ``kind``, ``state``, ``status``."""
        k = int(self.n[f])
        return {"xy": self.xy[f, :k].astype(np.float64), "kind": self.kind[:k], "state": self.state[f, :k],
                "status": self.status[f, :k]}

    def links(self, f: int) -> np.ndarray:
        """Links ``(M, 2)`` (``i < j``) of frame ``f``: stored ones, or the unit-disk pairs within ``r_c``."""
        if self.link_offsets is not None and self.link_pairs is not None:
            return self.link_pairs[self.link_offsets[f]: self.link_offsets[f + 1]]
        fr = self.frame(f)
        indptr, indices, _ = neighbour_csr(fr["xy"], self.r_c)
        pairs = pairs_from_csr(indptr, indices)
        failed = fr["state"] == State.FAILED
        return pairs[~(failed[pairs[:, 0]] | failed[pairs[:, 1]])] if failed.any() else pairs

    def trails(self, f: int) -> dict[int, np.ndarray]:
        """Agent id → its path ``(f + 1, 2)`` over frames ``0..f``."""
        agents = np.flatnonzero(self.kind == Role.AGENT)
        return {int(a): self.xy[: f + 1, a].astype(np.float64) for a in agents if a < self.n[f]}

    @property
    def medium(self) -> RadioMedium:
        """The run's radio medium, rebuilt from ``meta`` (model, link budget, seed) over the recorded map.

        Its shadowing field is the run's (the run's generator spawns it first; a fresh generator of the seed
        spawns the same). Packet loss is left off: it decides nothing that a picture shows. Without a recorded
        budget (older recordings): the unit disk of ``r_c``.
        """
        if self._medium is None:
            if self.budget is None:
                self._medium = make_medium("unit-disk", self.r_c, self.omap)
            else:
                self._medium = make_medium(self.meta["medium"], self.budget, self.omap,
                                           rng=np.random.default_rng(int(self.meta["seed"])))
        return self._medium

    def network_xy(self, f: int) -> np.ndarray:
        """Positions ``(k, 2)`` of the nodes that relay in frame ``f`` (see ``Swarm.relaying``).

        Routers and base nodes, less the failed ones and those dropped but not relaying yet.
        """
        fr = self.frame(f)
        silent = state_lookup((State.DROPPED, State.FAILED))[fr["state"]]
        return fr["xy"][(fr["kind"] != Role.AGENT) & ~silent]

    def covered(self, f: int) -> np.ndarray:
        """Cells of the area that counts where a receiver hears a router or base node of frame ``f``.

        Under the unit disk: the cells within ``r_c`` (Eq. 1 raster); under another medium, the cells it hears
        (walls, shadowing), as the run counted them.
        """
        if self._coverage is None:
            self._coverage = CoverageArea(self.omap, self.reachable)
        return self.medium.covered_mask(self._coverage, self.network_xy(f))

    def coverage(self, f: int) -> float:
        """Raster coverage (Eq. 1, under the run's medium) of frame ``f``."""
        return float(np.count_nonzero(self.covered(f)) / max(np.count_nonzero(self.reachable), 1))

    def signal(self, f: int, grid: OccupancyMap | None = None, floor_db: float = -30.0) -> np.ndarray:
        """Best RSSI (dBm) of the routers and base nodes of frame ``f`` at every cell centre of ``grid``.

        Args:
            f: The frame.
            grid: The cells to evaluate (default the recorded map; a coarser grid over it for small rasters).
            floor_db: NaN where every node is more than ``-floor_db`` dB below the usable threshold.
        """
        return self.medium.signal_dbm(self.omap if grid is None else grid, self.network_xy(f), floor_db)

    def names(self, f: int) -> tuple[np.ndarray, np.ndarray]:
        """Role and state names of the robots present in frame ``f`` (for the pictures)."""
        fr = self.frame(f)
        return np.array(ROLE_NAMES)[fr["kind"]], np.array(STATE_NAMES)[fr["state"]]


def load_recording(path: str | Path) -> Recording:
    """Load ``recording.npz``, or the one inside a run folder.

    Raises:
        AmronetError: The folder or file does not exist, or the recording needs more memory than is available.
        RecordingError: The file is not a recording, or is damaged or forged: one line naming the array and what is
            wrong (:func:`~amronet.outputs.recording_checks.read_recording_arrays`, :meth:`Recording.from_arrays`).
    """
    path = Path(path)
    if path.is_dir():
        folder, path = path, path / "recording.npz"
        if not path.is_file():
            raise AmronetError(f"{folder} has no recording.npz: run it again with --record")
    elif not path.exists():
        raise AmronetError(f"{path} does not exist: give a run folder written by amronet run --record")
    return Recording.from_arrays(read_recording_arrays(path), where=str(path))
