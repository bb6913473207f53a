"""``simmer plot``: a recorded run drawn into its folder."""

from __future__ import annotations

from typing import Annotated

import typer

from simmer.cli.app import Command, app, err, example, out
from simmer.cli.common import RunFolder, refuse_tap_folder

ScanAt = Annotated[
    float | None,
    typer.Option(
        "--scan-at",
        help="Also draw scan.png: the LiDAR scan that had ended by T seconds of the run "
        "(as sensors.png's time axis counts them), over the maze and as read.",
        metavar="T",
        min=0.0,
    ),
]


@app.command(
    cls=Command,
    short_help="Draw a recorded run: path.png, sensors.png, scans.",
    epilog=example("simmer plot runs/bias", "simmer plot runs/lidar --scan-at 2.5"),
)
def plot(folder: RunFolder, scan_at: ScanAt = None) -> None:
    """Draw a recorded run into its folder: path.png (the path over the maze, commands
    numbered, collisions marked) and sensors.png (readings against time); with a LiDAR,
    scans.png (every scan point over the maze) and, with --scan-at, scan.png; report.md
    links them."""
    from simmer.errors import PlotError
    from simmer.record.plots import plot_run

    refuse_tap_folder(folder, "draw")
    try:
        written = plot_run(
            folder, say=lambda line: out.print(line, markup=False), scan_time=scan_at
        )
    except PlotError as exc:
        err.print(str(exc), style="bold red", markup=False)
        raise typer.Exit(1) from None
    for path in written:
        out.print(f"wrote {path}", markup=False)
