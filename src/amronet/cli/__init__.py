"""The ``amronet`` command line: one module per group of subcommands, :func:`main` the entry point."""

from amronet.cli.main import main

__all__ = ["main"]
