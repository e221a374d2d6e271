"""The ``amronet`` command line: one module per group of subcommands, :func:`main` the entry point.

The command modules import what a subcommand needs inside the function that runs it, on purpose: building the
parser, ``amronet --help`` and a refused option then answer without loading the simulator, matplotlib or Dask.
Those lazy imports are the only ones in the package; everywhere else imports sit at the top of the module and
point down the layers (README, *Architecture*).
"""

from amronet.cli.main import main

__all__ = ["main"]
