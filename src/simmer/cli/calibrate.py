"""``simmer calibrate``: the routine to run on the real robot, and the fit of its run."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from simmer.cli.app import Command, app, err, example, out
from simmer.cli.common import report_config_error, seeds_check


@app.command(
    cls=Command,
    short_help="Fit the robot's noise settings from a tap's run of the routine.",
    epilog=example(
        "simmer calibrate --config robot.toml --routine calibration_routine.py",
        "simmer calibrate runs/calibration --out runs/calibration/fit",
    ),
)
def calibrate(
    run: Annotated[
        Path | None,
        typer.Argument(
            help="The tap's run folder of the routine (simmer tap --record DIR).",
            metavar="[DIR]",
            show_default=False,
        ),
    ] = None,
    config: Annotated[
        Path | None,
        typer.Option(
            help="The robot's configuration (default: the one the tap recorded).",
            metavar="CONFIG",
        ),
    ] = None,
    routine: Annotated[
        Path | None,
        typer.Option(
            help="Write the calibration routine for CONFIG's robot to this file and stop.",
            metavar="FILE",
        ),
    ] = None,
    out_dir: Annotated[
        Path | None,
        typer.Option(
            "--out",
            help="Folder for fitted.toml, calibration.md and its plots (default: DIR/fit).",
            metavar="OUT",
        ),
    ] = None,
    seeds: Annotated[
        int,
        typer.Option(
            help="Seeds for the report's predicted band.", metavar="N", callback=seeds_check
        ),
    ] = 100,
) -> None:
    """Calibrate SimMeR to the real robot. First write the routine (--routine FILE --config
    CONFIG) and run it on the robot through simmer tap; then give the tap's run folder: each
    drive's bias and error, each sensor's error and offset and the gyroscope's drift are
    fitted, each with its 99% interval, into OUT/fitted.toml, with a report and plots
    (docs/calibration.md)."""
    from simmer.calibrate.fit import calibrate as fit
    from simmer.calibrate.report import write_report
    from simmer.calibrate.routine import plan, routine_program
    from simmer.config import load_config
    from simmer.errors import ConfigError, RoutineError
    from simmer.tap.folder import load_tap_run

    try:
        settings = load_config(config) if config is not None else None
    except ConfigError as exc:
        report_config_error(exc)
        raise typer.Exit(1) from None
    try:
        if routine is not None:
            if settings is None:
                raise RoutineError("--routine needs --config: the robot's configuration")
            routine.write_text(routine_program(settings, plan(settings), routine.name))
            out.print(f"wrote {routine}: run it on the robot through simmer tap", markup=False)
            return
        if run is None:
            raise RoutineError("give the tap's run folder (DIR), or --routine FILE --config CONFIG")
        tapped = load_tap_run(run)
        settings = settings or tapped.config
        result = fit(tapped, settings)
        write_report(
            result,
            tapped,
            settings,
            out_dir or run / "fit",
            seeds=seeds,
            say=lambda line: out.print(line, markup=False),
        )
    except (ValueError, OSError, ConfigError) as exc:
        err.print(str(exc), style="bold red", markup=False)
        raise typer.Exit(1) from None
