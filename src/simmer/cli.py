"""The ``simmer`` command: run a simulation, check a configuration, and more."""

from __future__ import annotations

import logging
from pathlib import Path
from typing import Annotated

import typer
from rich.console import Console

from simmer.config import load_config, summarize
from simmer.errors import ConfigError

app = typer.Typer(
    name="simmer",
    help="SimMeR, the Simulator for Mechatronics Robots.",
    no_args_is_help=False,
    add_completion=False,
    pretty_exceptions_enable=False,
)
out = Console(highlight=False)
err = Console(stderr=True, highlight=False, soft_wrap=True)

ConfigArg = Annotated[
    Path | None,
    typer.Argument(
        help="Configuration file (.toml, or a SimMeR config.py). Default: the built-in lab maze "
        "and rover.",
        show_default=False,
    ),
]


def _report_config_error(exc: ConfigError) -> None:
    count = len(exc.issues)
    err.print(f"[bold red]{count} problem{'s' if count != 1 else ''} in {exc.source}:[/]")
    for issue in exc.issues:
        err.print(f"  {issue.render(exc.source)}", markup=False)


@app.command()
def check(
    config: Annotated[Path, typer.Argument(help="Configuration file to check.")],
) -> None:
    """Check a configuration: print OK and a summary, or every problem found (exit status 1)."""
    try:
        loaded = load_config(config)
    except ConfigError as exc:
        _report_config_error(exc)
        raise typer.Exit(1) from None
    out.print(f"[bold green]OK[/] {config}")
    out.print(summarize(loaded), markup=False)


@app.command()
def keys(
    markdown: Annotated[bool, typer.Option(help="Print the reference as Markdown.")] = False,
) -> None:
    """List every configuration key and device setting, with defaults."""
    from simmer.config.reference import reference_markdown

    text = reference_markdown()
    if markdown:
        print(text, end="")
    else:
        from rich.markdown import Markdown

        out.print(Markdown(text))


@app.command()
def run(
    config: ConfigArg = None,
    headless: Annotated[bool, typer.Option(help="Run without a window.")] = False,
    seconds: Annotated[
        float | None, typer.Option(help="Stop after this many simulated seconds.")
    ] = None,
    speed: Annotated[
        str, typer.Option(help="Speed as a multiple of real time (e.g. 2), or 'max'.")
    ] = "1",
    seed: Annotated[
        int | None, typer.Option(help="Noise seed (overrides the configuration's).")
    ] = None,
    host: Annotated[
        str | None,
        typer.Option(help="Address to listen on (default: the configuration's, 127.0.0.1)."),
    ] = None,
    port_rx: Annotated[
        int | None, typer.Option(help="SimMeR two-port scheme: message port (default 61200).")
    ] = None,
    port_tx: Annotated[
        int | None, typer.Option(help="SimMeR two-port scheme: reply port (default 61201).")
    ] = None,
    port: Annotated[int, typer.Option(help="Persistent protocol port.")] = 61202,
    serial: Annotated[
        bool, typer.Option(help="Also serve a virtual serial port (a pseudo-terminal).")
    ] = False,
    serial_link: Annotated[
        Path | None, typer.Option(help="Make a stable link to the serial port at this path.")
    ] = None,
) -> None:
    """Run the simulator on CONFIG (default: the built-in lab maze and rover)."""
    from simmer.serve import parse_speed
    from simmer.world import Simulation

    try:
        pace = parse_speed(speed)
    except ValueError as exc:
        raise typer.BadParameter(str(exc), param_hint="--speed") from None
    try:
        sim = Simulation(load_config(config), seed=seed)
    except ConfigError as exc:
        _report_config_error(exc)
        raise typer.Exit(1) from None
    out.print(summarize(sim.config), markup=False)
    out.print(f"noise seed {sim.seed}", markup=False)
    from simmer.errors import SimmerError
    from simmer.serve import serve

    try:
        serve(
            sim,
            window=not headless,
            speed=pace,
            seconds=seconds,
            host=host,
            port_rx=port_rx,
            port_tx=port_tx,
            stream_port=port,
            serial=serial,
            serial_link=serial_link,
            echo=lambda line: out.print(line, markup=False),
        )
    except SimmerError as exc:
        err.print(f"[bold red]{exc}[/]")
        raise typer.Exit(1) from None
    except OSError as exc:
        err.print(f"[bold red]cannot serve: {exc}[/] (is another simmer running?)")
        raise typer.Exit(1) from None
    out.print(f"t = {sim.time:.2f} s, robot at {sim.robot.pose}", markup=False)


@app.command()
def convert(
    config: Annotated[Path, typer.Argument(help="A SimMeR config.py to convert.")],
    output: Annotated[
        Path | None,
        typer.Option("--output", "-o", help="TOML file to write (default: print it)."),
    ] = None,
) -> None:
    """Convert a SimMeR config.py to the native TOML format, keeping its comments."""
    from simmer.config.convert import convert_simmer_py

    try:
        text = convert_simmer_py(config, output)
    except ConfigError as exc:
        _report_config_error(exc)
        raise typer.Exit(1) from None
    if output is None:
        out.print(text, markup=False, end="")
    else:
        out.print(f"[bold green]wrote[/] {output}; check it with `simmer check {output}`")


@app.command()
def console(
    host: Annotated[str, typer.Option(help="Simulator address.")] = "127.0.0.1",
    port: Annotated[int, typer.Option(help="Persistent protocol port.")] = 61202,
    two_port: Annotated[
        bool, typer.Option(help="Use SimMeR's two-port scheme (61200/61201) instead.")
    ] = False,
    serial: Annotated[
        str | None, typer.Option(help="Talk to a serial port (virtual or the robot's) instead.")
    ] = None,
    baud: Annotated[int, typer.Option(help="Serial baud rate.")] = 9600,
) -> None:
    """Interactive console: type commands (u0, w0-6, ...) and see the replies."""
    from simmer.client import connect
    from simmer.console import run_console
    from simmer.errors import ClientError

    try:
        client = connect(
            host, port, scheme="two-port" if two_port else None, serial=serial, baudrate=baud
        )
    except ClientError as exc:
        err.print(f"[bold red]{exc}[/]")
        raise typer.Exit(1) from None
    with client:
        run_console(client)


def main() -> None:
    """Entry point of the ``simmer`` console script."""
    logging.basicConfig(level=logging.INFO, format="%(levelname)s %(name)s: %(message)s")
    app()
