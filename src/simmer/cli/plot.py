"""``simmer plot``: a recorded run drawn into its folder."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from simmer.cli.app import Command, app, err, example, out
from simmer.cli.common import RunFolder, is_tap_run

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
    links them. A tap's run of the real robot (no true pose) gets timeline.png instead: the
    commands sent and the readings received, over time."""
    from simmer.errors import PlotError
    from simmer.record.plots import plot_run

    if is_tap_run(folder):
        _plot_tap_run(folder)
        return
    try:
        written = plot_run(
            folder, say=lambda line: out.print(line, markup=False), scan_time=scan_at
        )
    except PlotError as exc:
        err.print(str(exc), style="bold red", markup=False)
        raise typer.Exit(1) from None
    for path in written:
        out.print(f"wrote {path}", markup=False)


def _plot_tap_run(folder: Path) -> None:
    """timeline.png of a tap's run folder, or one plain line saying why not (exit 1)."""
    from simmer.errors import SimmerError
    from simmer.record.safefile import check_target
    from simmer.tap.folder import load_tap_run
    from simmer.tap.timeline import TIMELINE_IMAGE, draw_tap_timeline

    target = folder / TIMELINE_IMAGE
    try:
        run = load_tap_run(folder)
        check_target(target)
        draw_tap_timeline(run, target)
    except (OSError, ValueError, SimmerError) as exc:
        err.print(f"cannot draw {folder}: {exc}", style="bold red", markup=False)
        raise typer.Exit(1) from None
    out.print(
        f"{folder} is a tap's run of the real robot: no true pose, so no path; its commands "
        "and readings over time are drawn",
        markup=False,
    )
    out.print(f"wrote {target}", markup=False)
