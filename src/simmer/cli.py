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
    headless: Annotated[bool, typer.Option(help="Run without a window.")] = True,
    seconds: Annotated[
        float | None, typer.Option(help="Stop after this many simulated seconds.")
    ] = None,
) -> None:
    """Run the simulator on CONFIG (default: the built-in lab maze and rover)."""
    from simmer.world import Simulation

    try:
        sim = Simulation(load_config(config))
    except ConfigError as exc:
        _report_config_error(exc)
        raise typer.Exit(1) from None
    out.print(summarize(sim.config), markup=False)
    out.print(f"noise seed {sim.seed}; running headless", markup=False)
    steps = round((seconds if seconds is not None else 1.0) / sim.dt)
    sim.step(steps)
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


def main() -> None:
    """Entry point of the ``simmer`` console script."""
    logging.basicConfig(level=logging.INFO, format="%(levelname)s %(name)s: %(message)s")
    app()
