"""The ``simmer`` command: run a simulation, check a configuration, and more.

A module per command (as ``tests/cli/`` has a test file per command), each thin: typer parses
the flags, and a function that knows nothing of typer decides (``run``'s is
:meth:`RunOptions.from_flags <simmer.options.RunOptions.from_flags>`). A command imports what it
needs inside its function, so ``simmer --help`` answers at once. Importing a command's module
registers it on :data:`app`; they are imported here in the order ``simmer --help`` lists them.
"""

from __future__ import annotations

import logging

from simmer.cli.app import AS_COMMAND, app

# Each import registers a command, in the order simmer --help lists them (not sorted):
# isort: off
from simmer.cli import new, check, keys, run, convert, export_map, table  # noqa: F401
from simmer.cli import plot, replay, render, sweep, grade, console, maze  # noqa: F401
from simmer.cli import tap, calibrate, compare  # noqa: F401

# isort: on

__all__ = ["app", "main"]


def main() -> None:
    """Entry point of the ``simmer`` console script."""
    logging.basicConfig(level=logging.INFO, format="%(levelname)s %(name)s: %(message)s")
    for handler in logging.getLogger().handlers:
        handler.addFilter(_ours_or_a_warning)
    AS_COMMAND.append(True)
    app()


def _ours_or_a_warning(record: logging.LogRecord) -> bool:
    """What the terminal shows: SimMeR's own lines, and a library's warnings and errors only
    (Dask set its own loggers to INFO: a sweep on a local cluster printed 34 lines of it)."""
    return record.levelno >= logging.WARNING or record.name.split(".")[0] == "simmer"
