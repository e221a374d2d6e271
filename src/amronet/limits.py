"""Resource guards: what a job would cost, estimated from its inputs before anything is allocated.

Every entry point that allocates in proportion to a number the user gives (robots, map cells, steps, sweep
points, a recording's arrays, pattern lattice points, worker processes, the nodes of a signal map) first
multiplies that number by a documented cost per item and compares the result with the machine: a job that cannot
fit in the memory available now is refused (one line saying how much it would need and how much there is, and the
fix), and a job that fits but would take absurdly long is refused unless the user acknowledges it (``--force`` on
the command line, ``force=True`` in Python). Nothing is allocated or written before the check.

The per-item costs are measured peaks on 64-bit Linux with NumPy 2, rounded up (see each constant); the estimates
are deliberately coarse and err on the high side, since they guard the machine, not budget it. This module sits at
the bottom of the package (it imports only :mod:`amronet.errors`), so that every layer can use it.
"""

from __future__ import annotations

import math
import os
from pathlib import Path

from amronet.errors import AmronetError, ScenarioError

__all__ = [
    "ACKNOWLEDGE",
    "BYTES_PER_IMAGE_BAND",
    "BYTES_PER_IMAGE_PIXEL",
    "BYTES_PER_LATTICE_CANDIDATE",
    "BYTES_PER_LATTICE_POINT",
    "BYTES_PER_LINK",
    "BYTES_PER_MAP_CELL",
    "BYTES_PER_ROBOT",
    "BYTES_PER_SWEEP_POINT",
    "BYTES_PER_SWEEP_RUN",
    "BYTES_PER_WORKER",
    "MAX_COUNT",
    "MAX_PATTERN_WORK",
    "MAX_ROBOT_STEPS",
    "MAX_SIGNAL_WORK",
    "MAX_STEPS",
    "MAX_SWEEP_POINTS",
    "MAX_SWEEP_RUNS",
    "SIGNAL_CELL_WITHOUT_WALLS",
    "available_memory",
    "check_memory",
    "check_work",
    "format_bytes",
    "format_count",
]

# -- costs per item (bytes) ------------------------------------------------------------------------------------
BYTES_PER_ROBOT = 2048
"""A robot in a run: its state arrays, its rows in the controller's arrays, the motion and sensing temporaries.
Measured: 0.9 KiB (self-spreading, potential field) to 1.6 KiB (DSSA) per robot at a mean degree of 12
(``amronet bench``, 10^5 to 3 x 10^5 robots); links beyond that are counted by :data:`BYTES_PER_LINK`."""

BYTES_PER_LINK = 64
"""A directed link of the neighbour table: neighbour id, length, margin, and the controllers' per-link arrays."""

BYTES_PER_MAP_CELL = 64
"""A map cell in a run: the grid, clearance (and its distance transform), reachable space, coverage raster, the
radio's rasters. Measured peaks: 37 B (unit disk) to 60 B (log-distance, multi-wall) per cell on a 4 000 x 4 000
map."""

BYTES_PER_IMAGE_BAND = 8
"""Decoding a map image: a float64 copy of each colour band of a pixel, plus :data:`BYTES_PER_IMAGE_PIXEL` (measured
20 B per pixel for grey, 36 B for RGB)."""

BYTES_PER_IMAGE_PIXEL = 16
"""Decoding a map image, per pixel besides its bands: the grey value, the occupancy probability, the masks, the
grid."""

BYTES_PER_SWEEP_POINT = 8192
"""A sweep point held in memory: its resolved scenario, overrides and hash (measured 2.7 KiB) and the
validation's temporaries."""

BYTES_PER_SWEEP_RUN = 1024
"""A (point, seed) run of a sweep while it is scheduled and recorded."""

BYTES_PER_WORKER = 128 * 2**20
"""A worker process of a pool (local, or a Dask ``LocalCluster``'s), besides the runs it holds (each counted by its
run's guard). Measured after a run of ``self-spreading-6x6``: a forked pool worker 121 MiB resident (20 MiB of it
private, the rest shared with its parent until written), a fresh interpreter importing amronet 146 MiB (71 MiB
private); counted at about a forked worker's resident size, for the pages a long run makes its own."""

BYTES_PER_LATTICE_CANDIDATE = 32
"""A lattice point of a pattern per candidate offset of the placement search: its inside flag and, once the
candidate is evaluated, its ``(x, y)`` (measured up to 31 B); a point costs this times the candidate offsets, plus
:data:`BYTES_PER_LATTICE_POINT` for the point itself."""

BYTES_PER_LATTICE_POINT = 256
"""A lattice point of a pattern: its coordinates and indices, and their temporaries while they are generated."""

# -- thresholds of absurd work (refused unless acknowledged) -----------------------------------------------------
MAX_STEPS = 10**7
"""Steps of one run (``sim.time_limit / sim.dt``): a step of a small swarm takes 0.4 to 0.9 ms on a 2-core
machine, so 10^7 steps are one to three hours, or 12 simulated days at the default ``dt`` of 0.1 s."""

MAX_ROBOT_STEPS = 10**9
"""Robots times steps of one run: about 2 x 10^5 robot-steps per second on a 2-core machine (``amronet bench``),
so 10^9 is about an hour and a half."""

MAX_SWEEP_POINTS = 100_000
"""Points of one sweep (its grid's product plus its explicit points): each is validated (about 0.6 ms) and its
start set up before anything runs."""

MAX_SWEEP_RUNS = 1_000_000
"""Runs of one sweep (points times seeds): at a tenth of a second each, more than a day on two cores."""

MAX_PATTERN_WORK = 20_000_000
"""Lattice points times candidate offsets of one pattern placement (about 6 us each on a 2-core machine): two
minutes a pattern; at the default 16 steps (about 720 offsets) some 28 000 lattice points, e.g. 160 m x 160 m at
``r`` = 1 m."""

MAX_SIGNAL_WORK = 2 * 10**8
"""Nodes times the map cells within each one's signal reach, of one signal map (``amronet radio-map``): about 0.3 us
each when walls are counted, on an idle 2-core machine (263 nodes over the 409 600 cells of ``office-32x32`` under
``multi-wall``, 1.1 x 10^8, took 30 s; two to three times that while other jobs ran), so a minute. A cell of a
radio without walls counts :data:`SIGNAL_CELL_WITHOUT_WALLS`."""

SIGNAL_CELL_WITHOUT_WALLS = 0.125
"""What a node-cell costs without walls to count, as a share of one with them (measured: a fifteenth for the unit
disk, a ninth for ``log-distance``)."""

MAX_COUNT = 10**12
"""The largest whole number a scenario field takes (robots, node ids, steps of a rule, steps between records): far
more than any machine holds (10^9 robots at :data:`BYTES_PER_ROBOT` are 2 TB) or steps through, and exact in a
float and in the compiled kernels' 64-bit integers, which a larger one would overflow."""

ACKNOWLEDGE = "or acknowledge it with --force (force=True in Python)"
"""How a user acknowledges absurd work, as the messages say it."""


# -- the machine -----------------------------------------------------------------------------------------------
def _meminfo_available() -> int | None:
    try:
        for line in Path("/proc/meminfo").read_text().splitlines():
            if line.startswith("MemAvailable:"):
                return int(line.split()[1]) * 1024
    except (OSError, ValueError, IndexError):
        pass
    return None


def _sysconf_available() -> int | None:
    try:
        pages, size = os.sysconf("SC_AVPHYS_PAGES"), os.sysconf("SC_PAGE_SIZE")
    except (AttributeError, OSError, ValueError):
        return None
    return pages * size if pages > 0 and size > 0 else None


def _cgroup_available() -> int | None:
    """Room left under a cgroup v2 memory limit (a container's), if there is one."""
    try:
        limit = Path("/sys/fs/cgroup/memory.max").read_text().strip()
        if limit == "max":
            return None
        return max(int(limit) - int(Path("/sys/fs/cgroup/memory.current").read_text().strip()), 0)
    except (OSError, ValueError):
        return None


def _rlimit_available() -> int | None:
    """Room left under this process's address-space limit (``ulimit -v``), if there is one."""
    try:
        import resource

        soft, _ = resource.getrlimit(resource.RLIMIT_AS)
        if soft == resource.RLIM_INFINITY or soft <= 0:
            return None
        used = int(Path("/proc/self/statm").read_text().split()[0]) * os.sysconf("SC_PAGE_SIZE")
    except (ImportError, OSError, ValueError, IndexError, AttributeError):
        return None
    return max(soft - used, 0)


def available_memory() -> int | None:
    """Bytes this process can still allocate without swapping, or ``None`` when the machine does not say.

    The least of: ``MemAvailable`` of ``/proc/meminfo`` (else ``os.sysconf``'s available physical pages), the room
    under a cgroup v2 memory limit and the room under the address-space limit (``ulimit -v``). Without any of them
    the memory checks pass (the work checks still apply).
    """
    system = _meminfo_available()
    if system is None:
        system = _sysconf_available()
    known = [v for v in (system, _cgroup_available(), _rlimit_available()) if v is not None]
    return min(known) if known else None


def format_bytes(n: float) -> str:
    """``n`` bytes for a person: ``512 B``, ``3.2 MiB``, ``41 GiB``, ``7.2 TiB``."""
    if not math.isfinite(n):
        return "an unbounded amount"
    units = ("B", "KiB", "MiB", "GiB", "TiB", "PiB", "EiB")
    k = 0
    while n >= 1024 and k < len(units) - 1:
        n /= 1024
        k += 1
    return f"{n:.0f} {units[k]}" if k == 0 or n >= 100 else f"{n:.3g} {units[k]}"


def format_count(n: float) -> str:
    """A count for a person: ``1,001,000,000`` (exact below 10^15), else ``3e+302``."""
    return f"{round(n):,}" if math.isfinite(n) and abs(n) < 1e15 else f"{n:.3g}"


# -- the checks ------------------------------------------------------------------------------------------------
def _error(error: type[AmronetError], field: str, message: str) -> AmronetError:
    if issubclass(error, ScenarioError):
        return error(field, message)
    return error(f"{field}: {message}" if field else message)


def check_memory(need: float, field: str, what: str, fix: str,
                 error: type[AmronetError] = ScenarioError) -> None:
    """Refuse a job whose estimated memory ``need`` (bytes) exceeds what the machine has available now.

    Args:
        need: The estimate in bytes.
        field: The field or option to name (``routers.count``, ``--robots``, ``map.image``).
        what: The job, as the message starts: ``"3000000 robots"``.
        fix: How to make it fit: ``"use fewer routers"``.
        error: The exception class to raise (a :class:`ScenarioError` takes the field separately).

    Raises:
        AmronetError: ``error(field, "WHAT would need about X of memory, but Y are available; FIX")``. Not
            acknowledgeable: a job that does not fit fails anyway, later and worse.
    """
    avail = available_memory()
    if avail is None or need <= avail:
        return
    raise _error(error, field, f"{what} would need about {format_bytes(need)} of memory, but "
                               f"{format_bytes(avail)} are available; {fix}")


def check_work(amount: float, limit: float, field: str, what: str, fix: str, force: bool,
               error: type[AmronetError] = ScenarioError, acknowledge: str = ACKNOWLEDGE) -> None:
    """Refuse absurd work (``amount`` above ``limit``) unless the user acknowledged it with ``force``.

    Args:
        amount: The work, in the unit of ``limit`` (steps, robot-steps, points, ...).
        limit: The most that runs without acknowledgement (a ``MAX_*`` constant of this module).
        field: The field or option to name.
        what: The work, as the message starts: ``"1e+13 steps (sim.time_limit 1e+12 s / sim.dt 0.1 s)"``.
        fix: How to make it smaller.
        force: The user's acknowledgement: with it nothing is refused.
        error: The exception class to raise.
        acknowledge: How the user can acknowledge it, the message's last clause.

    Raises:
        AmronetError: ``error(field, "WHAT would take absurdly long (the limit without acknowledgement is L);
            FIX, ACKNOWLEDGE")``.
    """
    if force or amount <= limit:
        return
    raise _error(error, field, f"{what} would take absurdly long (the limit without acknowledgement is "
                               f"{format_count(limit)}); {fix}, {acknowledge}")
