"""Sweeps: many seeded runs over a grid of parameters, on a laptop or a Dask cluster, into a result store.

* :mod:`~amronet.sweeps.spec` — sweep files: base scenario, grid / points of overrides, seeds; validated.
* :mod:`~amronet.sweeps.check` — every distinct start of a sweep set up once (maps, base stations) before it runs.
* :mod:`~amronet.sweeps.identity` — a run's identity: the resolved scenario's canonical JSON and map content, hashed.
* :mod:`~amronet.sweeps.store` — the SQLite result store (WAL; one transaction per finished run).
* :mod:`~amronet.sweeps.executors` — a local process pool and a Dask executor behind one interface.
* :mod:`~amronet.sweeps.engine` — run what is missing, record as it finishes, with a progress bar; Ctrl-C stops
  at once with :class:`~amronet.sweeps.interrupt.SweepInterrupted`, which counts what the store holds.
* :mod:`~amronet.sweeps.tables` and :mod:`~amronet.sweeps.plot` — tidy tables, CSV/Parquet export, plots.

Example:
    >>> import tempfile, pathlib
    >>> from amronet.sweeps import LocalExecutor, load_sweep, run_sweep
    >>> sweep = load_sweep({"name": "demo", "base": "self-spreading-6x6", "overrides": {"sim.time_limit": 1},
    ...                     "grid": {"radio.r_c": [0.8, 1.0]}, "seeds": 2})
    >>> store = pathlib.Path(tempfile.mkdtemp()) / "results.sqlite"
    >>> report = run_sweep(sweep, store, LocalExecutor(1), show_progress=False)
    >>> report.total, report.done, run_sweep(sweep, store, LocalExecutor(1), show_progress=False).already
    (4, 4, 4)
"""

from amronet.sweeps.engine import SweepReport, execute_into_store, pending_runs, run_sweep
from amronet.sweeps.executors import (
    ClusterLostError,
    DaskExecutor,
    Executor,
    LocalExecutor,
    default_workers,
    make_executor,
)
from amronet.sweeps.identity import canonical_json, resolve_scenario, scenario_hash
from amronet.sweeps.interrupt import SweepInterrupted
from amronet.sweeps.spec import Point, Sweep, SweepSpec, load_sweep, sweep_from_spec
from amronet.sweeps.store import ResultStore, StoreError

__all__ = [
    "ClusterLostError",
    "DaskExecutor",
    "Executor",
    "LocalExecutor",
    "Point",
    "ResultStore",
    "StoreError",
    "Sweep",
    "SweepInterrupted",
    "SweepReport",
    "SweepSpec",
    "canonical_json",
    "default_workers",
    "execute_into_store",
    "load_sweep",
    "make_executor",
    "pending_runs",
    "resolve_scenario",
    "run_sweep",
    "scenario_hash",
    "sweep_from_spec",
]
