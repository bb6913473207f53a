"""``simmer export-map``: the maze as JSON, as ``robot.maze()`` gives it."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from simmer.cli.app import Command, app, err, example, out
from simmer.cli.common import ConfigArg, simulation


@app.command(
    "export-map",
    cls=Command,
    short_help="Write the maze as JSON, as robot.maze() gives it.",
    epilog=example("simmer export-map my_rover.toml -o maze.json"),
)
def export_map(
    config: ConfigArg = None,
    output: Annotated[
        Path, typer.Option("--output", "-o", help="JSON file to write.", metavar="FILE")
    ] = Path("maze.json"),
) -> None:
    """Write the maze as a program may know it (walls, sizes, wall segments, floor, zones, the
    configured start, every device's mount) as JSON: what robot.maze() answers, for a program
    that also runs on the real robot. docs/localization.md says what each key means."""
    from simmer.localize.files import write_map

    sim = simulation(config)
    try:
        write_map(sim, output)
    except OSError as exc:
        err.print(f"cannot write {output}: {exc}", style="bold red", markup=False)
        raise typer.Exit(1) from None
    out.print(f"wrote {output}", markup=False)
