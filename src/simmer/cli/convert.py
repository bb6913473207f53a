"""``simmer convert``: a SimMeR config.py as a native TOML file."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer
from rich.text import Text

from simmer.cli.app import Command, app, example, out
from simmer.cli.common import report_config_error
from simmer.errors import ConfigError


@app.command(
    cls=Command,
    short_help="Convert a SimMeR config.py to the native TOML format.",
    epilog=example("simmer convert config.py -o my_rover.toml"),
)
def convert(
    config: Annotated[
        Path, typer.Argument(help="A SimMeR config.py to convert.", metavar="CONFIG")
    ],
    output: Annotated[
        Path | None,
        typer.Option(
            "--output", "-o", help="TOML file to write (default: print it).", metavar="FILE"
        ),
    ] = None,
) -> None:
    """Convert a SimMeR config.py to the native TOML format, keeping its comments."""
    from simmer.config.convert import convert_simmer_py

    try:
        text = convert_simmer_py(config, output)
    except ConfigError as exc:
        report_config_error(exc)
        raise typer.Exit(1) from None
    if output is None:
        out.print(text, markup=False, end="")
    else:
        out.print(
            Text.assemble(
                ("wrote", "bold green"), f" {output}; check it with `simmer check {output}`"
            )
        )
