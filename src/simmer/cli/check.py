"""``simmer check``: a configuration checked, and each device called once."""

from __future__ import annotations

import contextlib
import os
from collections.abc import Iterator
from pathlib import Path
from typing import Annotated, NoReturn

import typer
from rich.text import Text

from simmer.cli.app import Command, app, err, example, out
from simmer.cli.common import report_config_error, report_config_warnings
from simmer.errors import ConfigError, ExitCalled


@app.command(
    cls=Command,
    short_help="Check a configuration: OK and a summary, or every problem.",
    epilog=example("simmer check my_rover.toml"),
)
def check(
    config: Annotated[Path, typer.Argument(help="Configuration file to check.", metavar="CONFIG")],
) -> None:
    """Check a configuration and call each device once: print OK and a summary, or every
    problem found, each with its file, line, key and fix (exit status 1)."""
    from simmer.config import load_config, summarize
    from simmer.config.loader import placed_issues

    with _exit_refused():
        try:
            loaded = load_config(config)
        except ConfigError as exc:
            report_config_error(exc)
            raise typer.Exit(1) from None
        report_config_warnings(loaded)
        if loaded.origin:
            out.print(loaded.origin, markup=False)
        from simmer.world.probe import probe_devices

        issues = probe_devices(loaded)
    if issues:
        report_config_error(ConfigError(config, placed_issues(config, issues)))
        raise typer.Exit(1)
    out.print(Text.assemble(("OK", "bold green"), f" {config}"))
    ports = _ports(loaded.settings.port_rx, loaded.settings.port_tx)
    out.print(summarize(loaded, ports=ports), markup=False)
    if ports is None:
        out.print("Ports: free ones, printed when simmer run starts (SIMMER_PORTS=auto).")
    out.print(
        "Other ports for every command, the client and the examples: SIMMER_PORTS=62000 "
        "(62000-62002) in the terminal's environment, or simmer run --ports 62000 "
        "(--ports auto: free ones, printed).",
        markup=False,
    )


def _ports(port_rx: int, port_tx: int) -> tuple[int, int, int] | None:
    """The three ports ``simmer run`` would serve on in this terminal: ``SIMMER_PORTS``'s if
    it names them (it is checked: a wrong one is a plain line and exit status 1; ``auto`` is
    None, free ones chosen at start), else the configuration's and SimMeR's persistent one."""
    from simmer.errors import PortsError
    from simmer.ports import Ports, environment_ports

    try:
        chosen = environment_ports() or Ports()
    except PortsError as exc:
        err.print(str(exc), style="bold red", markup=False)
        raise typer.Exit(1) from None
    return None if chosen == Ports.free() else chosen.resolve(port_rx, port_tx)


@contextlib.contextmanager
def _exit_refused() -> Iterator[None]:
    """Within ``with``: ``os._exit(n)`` raises :class:`ExitCalled` (a ``SystemExit``, which
    check reports as a plug-in's or device's problem) instead of ending the process with no
    word: the code ``check`` imports and calls is the user's."""
    real = os._exit

    def refused(status: int) -> NoReturn:
        raise ExitCalled(f"os._exit({status}) was called")

    os._exit = refused
    try:
        yield
    finally:
        os._exit = real
