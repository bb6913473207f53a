"""``simmer compare``: the real robot's readings against the band the simulator predicts."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from simmer.cli.app import Command, app, err, example, out
from simmer.cli.common import report_config_error, seeds_check


@app.command(
    cls=Command,
    short_help="Does my simulator match my robot? Real readings in its band.",
    epilog=example(
        "simmer compare runs/real1 --config robot.toml",
        "simmer compare runs/real1 --config robot.toml --fitted runs/calibration/fit/fitted.toml",
    ),
)
def compare(
    run: Annotated[
        Path, typer.Argument(help="A tap's run folder (simmer tap --record DIR).", metavar="DIR")
    ],
    config: Annotated[
        Path,
        typer.Option(help="The configuration to compare the robot with.", metavar="CONFIG"),
    ],
    fitted: Annotated[
        Path | None,
        typer.Option(
            help="A fragment (simmer calibrate's fitted.toml) applied over CONFIG.", metavar="FILE"
        ),
    ] = None,
    seeds: Annotated[
        int, typer.Option(help="Seeds simulated.", metavar="N", callback=seeds_check)
    ] = 100,
    output: Annotated[
        Path | None,
        typer.Option(
            "-o", "--output", help="The picture (default: DIR/compare.png).", metavar="PNG"
        ),
    ] = None,
) -> None:
    """Drive the real run's commands in the simulator over many seeds and draw each real
    reading against the band (99%) the simulator predicts for it; the readings outside are
    named. Exit status 0 either way: read the picture."""
    import tomllib

    from simmer.calibrate.compare import compare as run_compare
    from simmer.calibrate.compare import draw_comparison
    from simmer.config import load_config
    from simmer.config.overrides import with_overrides
    from simmer.errors import ConfigError
    from simmer.tap.folder import load_tap_run

    try:
        settings = load_config(config)
        if fitted is not None:
            settings = with_overrides(
                settings, _dotted(tomllib.loads(fitted.read_text())), str(fitted)
            )
    except ConfigError as exc:
        report_config_error(exc)
        raise typer.Exit(1) from None
    except (OSError, UnicodeError, tomllib.TOMLDecodeError) as exc:
        err.print(f"cannot read {fitted}: {exc}", style="bold red", markup=False)
        raise typer.Exit(1) from None
    try:
        tapped = load_tap_run(run)
        comparison = run_compare(tapped, settings, seeds=seeds)
        picture = output or run / "compare.png"
        draw_comparison(comparison, picture, f"{run.name} against {config.name}")
    except (ValueError, OSError) as exc:
        err.print(str(exc), style="bold red", markup=False)
        raise typer.Exit(1) from None
    for line in comparison.summary():
        out.print(line, markup=False)
    out.print(f"wrote {picture}", markup=False)


def _dotted(data: dict[str, object], prefix: str = "") -> dict[str, object]:
    """A TOML document's values by dotted key (``drives.w0.bias.y``)."""
    flat: dict[str, object] = {}
    for key, value in data.items():
        if isinstance(value, dict):
            flat.update(_dotted(value, f"{prefix}{key}."))
        else:
            flat[f"{prefix}{key}"] = value
    return flat
