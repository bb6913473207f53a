"""``simmer compare``: the real robot's readings against the band the simulator predicts."""

from __future__ import annotations

import math
from pathlib import Path
from typing import TYPE_CHECKING, Annotated

import typer

from simmer.cli.app import Command, app, err, example, out
from simmer.cli.common import report_config_error, seeds_check

if TYPE_CHECKING:
    from simmer.calibrate.stats import Interval


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
    use_intervals: Annotated[
        bool,
        typer.Option(
            "--intervals/--point-values",
            help="With --fitted: each seed draws the fitted settings from the fit's intervals "
            "(the file simmer calibrate writes beside it), or takes the fitted values as they "
            "are.",
        ),
    ] = True,
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

    intervals: dict[str, Interval] = {}
    try:
        settings = load_config(config)
        if fitted is not None:
            values = _dotted(tomllib.loads(fitted.read_text()))
            settings = with_overrides(settings, values, str(fitted))
            if use_intervals:
                intervals = _intervals(fitted, values)
    except ConfigError as exc:
        report_config_error(exc)
        raise typer.Exit(1) from None
    except (OSError, UnicodeError, tomllib.TOMLDecodeError) as exc:
        err.print(f"cannot read {fitted}: {exc}", style="bold red", markup=False)
        raise typer.Exit(1) from None
    except ValueError as exc:
        err.print(str(exc), style="bold red", markup=False)
        raise typer.Exit(1) from None
    try:
        tapped = load_tap_run(run)
        comparison = run_compare(tapped, settings, seeds=seeds, intervals=intervals)
        picture = output or run / "compare.png"
        draw_comparison(comparison, picture, f"{run.name} against {config.name}")
    except (ValueError, OSError) as exc:
        err.print(str(exc), style="bold red", markup=False)
        raise typer.Exit(1) from None
    for line in comparison.summary():
        out.print(line, markup=False)
    out.print(f"wrote {picture}", markup=False)


def _intervals(fitted: Path, values: dict[str, object]) -> dict[str, Interval]:
    """The fit's intervals kept beside ``fitted``, for the settings it still holds at the
    values they were fitted at (one edited by hand is compared as it is), saying which."""
    from simmer.calibrate.compare import load_intervals
    from simmer.calibrate.fit import intervals_path

    path = intervals_path(fitted)
    if not path.is_file():
        out.print(
            f"no intervals beside {fitted} ({path.name}): the fitted values are compared as "
            "they are",
            markup=False,
        )
        return {}
    kept: dict[str, Interval] = {}
    for key, interval in load_intervals(path).items():
        value = values.get(key)
        if isinstance(value, int | float) and math.isclose(
            value, interval.value, rel_tol=1e-4, abs_tol=1e-6
        ):
            kept[key] = interval
        else:
            out.print(
                f"{key}: {fitted} no longer holds the value its interval was fitted at: "
                "compared at the file's value",
                markup=False,
            )
    out.print(
        f"each seed draws {len(kept)} fitted settings from the intervals in {path} "
        "(--point-values: the fitted values alone)",
        markup=False,
    )
    return kept


def _dotted(data: dict[str, object], prefix: str = "") -> dict[str, object]:
    """A TOML document's values by dotted key (``drives.w0.bias.y``)."""
    flat: dict[str, object] = {}
    for key, value in data.items():
        if isinstance(value, dict):
            flat.update(_dotted(value, f"{prefix}{key}."))
        else:
            flat[f"{prefix}{key}"] = value
    return flat
