"""``simmer table``: a lookup table of noise-free readings at every pose."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from simmer.cli.app import Command, app, err, example, out
from simmer.cli.common import ConfigArg, simulation


@app.command(
    cls=Command,
    short_help="Write a lookup table of noise-free readings at every pose.",
    epilog=example("simmer table my_rover.toml --step 1 --headings 0:360:1 -o table.npz"),
)
def table(
    config: ConfigArg = None,
    output: Annotated[
        Path,
        typer.Option("--output", "-o", help="Table to write: .npz or .csv.", metavar="FILE"),
    ] = Path("table.npz"),
    step: Annotated[
        float, typer.Option(help="Inches between positions (x and y).", metavar="INCHES")
    ] = 1.0,
    headings: Annotated[
        str, typer.Option(help="Headings START:STOP:STEP in degrees.", metavar="RANGE")
    ] = "0:360:1",
    sensor: Annotated[
        list[str] | None,
        typer.Option(
            help="A sensor to include (repeat it; default: every one it can).", metavar="ID"
        ),
    ] = None,
) -> None:
    """Write the readings each sensor gives with its noise off at every position (every STEP
    inches, half a step from the walls' lines) and heading, from the walls alone (no block):
    ultrasonic, infrared, compass and time-of-flight sensors, with the simulator's own
    geometry. A LiDAR (--sensor l0, alone): its scans at heading 0, which every heading
    rotates."""
    from rich.progress import Progress

    from simmer.localize.files import lidar_table, write_table
    from simmer.world.expected import parse_headings

    sim = simulation(config)
    lidars = [i for i in sensor or [] if getattr(sim.robot.sensors.get(i), "kind", "") == "lidar"]
    try:
        if lidars and len(sensor or []) > 1:
            raise ValueError(
                f"a LiDAR's table is written alone: give --sensor {lidars[0]} only (its scans "
                "at heading 0; every other heading is one rotated)"
            )
        angles = parse_headings(headings)
        with Progress(console=err, transient=True) as progress:
            task = progress.add_task("casting rays", total=None)
            done = lambda row, rows: progress.update(task, completed=row, total=rows)  # noqa: E731
            if lidars:
                count, ids = lidar_table(sim, step, lidars[0], output, done), lidars
            else:
                count, ids = write_table(sim, output, step, angles, sensor, done)
    except (ValueError, OSError) as exc:
        err.print(f"cannot write the table: {exc}", style="bold red", markup=False)
        raise typer.Exit(1) from None
    out.print(f"wrote {output}: {count:,} readings of {', '.join(ids)}", markup=False)
    if lidars:
        out.print(
            "a LiDAR's table is its scans facing heading 0 (--headings is not used): facing "
            "heading h it reads the same scan rotated by h (docs/localization.md)",
            markup=False,
        )
