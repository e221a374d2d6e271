"""The ``amronet`` command line: one module per group of subcommands, :func:`main` the entry point.

The command modules import what a subcommand needs inside the function that runs it, on purpose: building the
parser, ``amronet --help``, a refused option and a scenario file that does not exist then answer without loading
the simulator, numba, scipy, matplotlib or Dask (``tests/test_cli_startup.py``). The few other imports deferred
for that reason are in ``amronet/__init__.py`` and ``amronet.scenario`` (their public names load on first use),
:mod:`amronet.scenario.loading` and :mod:`amronet.scenario.overrides` (the schema and the radio models' registry)
and :mod:`amronet.numba_setup`; everywhere else imports sit at the top of the module and point down the layers
(README, *Architecture*).
"""

from amronet.cli.main import main

__all__ = ["main"]
