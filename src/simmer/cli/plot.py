"""``simmer plot``: a recorded run drawn into its folder."""

from __future__ import annotations

import typer

from simmer.cli.app import Command, app, err, example, out
from simmer.cli.common import RunFolder, refuse_tap_folder


@app.command(
    cls=Command,
    short_help="Draw a recorded run: path.png and sensors.png.",
    epilog=example("simmer plot runs/bias"),
)
def plot(folder: RunFolder) -> None:
    """Draw a recorded run into its folder: path.png (the path over the maze, commands
    numbered, collisions marked) and sensors.png (readings against time); report.md links
    them."""
    from simmer.errors import PlotError
    from simmer.record.plots import plot_run

    refuse_tap_folder(folder, "draw")
    try:
        written = plot_run(folder, say=lambda line: out.print(line, markup=False))
    except PlotError as exc:
        err.print(str(exc), style="bold red", markup=False)
        raise typer.Exit(1) from None
    for path in written:
        out.print(f"wrote {path}", markup=False)
