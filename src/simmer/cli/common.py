"""What more than one command shares: the configuration and run-folder arguments, the check of
a numeric flag, and how a configuration's problems are printed."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING, Annotated

import typer

from simmer.cli.app import err
from simmer.errors import ConfigError

if TYPE_CHECKING:
    from simmer.config import SimConfig
    from simmer.world import Simulation

MAX_SIMULATED_SECONDS = 1e9
"""Largest ``--seconds``, ``--link-delay`` and ``--max-seconds``: the longest ``!sleep`` (a
command's ``MAX_ABS_VALUE``), some 30 years of simulated time; NaN, infinities and negative
numbers are refused too (``--seconds nan`` ran no step and reported success)."""


def number_check(
    flag: str, unit: str, high: float, limit: str, *, zero: bool = False, low: float = 0.0
) -> Callable[[float | None], float | None]:
    """A numeric flag's check, run before the number is used: finite, more than ``low`` (or
    equal to it with ``zero``) and at most ``high`` (the constant named ``limit``); else one
    plain line saying so."""

    def check(value: float | None) -> float | None:
        if value is None or ((low <= value if zero else low < value) and value <= high):
            return value  # NaN fails both comparisons
        least = f"{low:g} or more" if zero else f"more than {low:g}"
        raise typer.BadParameter(
            f"{value!r} {unit}; give a number {least} and at most {high:,.0f} ({limit}; "
            "SimMeR's limits are in docs/limits.md)",
            param_hint=flag,
        )

    return check


MAX_SEEDS = 10_000
"""Most seeds ``simmer compare`` and ``simmer calibrate`` simulate (each re-simulates the whole
run: 0.09 s of CPU for the calibration routine's)."""


def seeds_check(value: int) -> int:
    """``--seeds``: 1 to :data:`MAX_SEEDS`, else one plain line naming the limit."""
    if not 1 <= value <= MAX_SEEDS:
        raise typer.BadParameter(
            f"{value} seeds; give 1 to {MAX_SEEDS:,} (MAX_SEEDS; SimMeR's limits are in "
            "docs/limits.md)",
            param_hint="--seeds",
        )
    return value


ConfigArg = Annotated[
    Path | None,
    typer.Argument(
        help="Configuration file (.toml, or a SimMeR config.py). Default: the built-in lab maze "
        "and rover.",
        show_default=False,
        metavar="CONFIG",
    ),
]
RunFolder = Annotated[
    Path, typer.Argument(help="A run folder (simmer run --record DIR).", metavar="DIR")
]


def report_config_error(exc: ConfigError) -> None:
    """Print every problem of a configuration, each with its file, line, key and fix."""
    count = len(exc.issues)
    err.print(f"{count} problem{'s' if count != 1 else ''} in {exc.source}:", style="bold red")
    for issue in exc.issues:
        err.print(f"  {issue.render(exc.source)}", markup=False)


def report_config_warnings(config: SimConfig) -> None:
    """Print what an original config.py does that a native file may not (it still runs)."""
    count = len(config.warnings)
    if count:
        err.print(
            f"{count} warning{'s' if count != 1 else ''} in {config.source}:", style="bold yellow"
        )
    for issue in config.warnings:
        err.print(f"  {issue.render(config.source)}", markup=False, style="yellow")


def simulation(config: Path | None) -> Simulation:
    """The simulation of a configuration, or its problems and exit status 1."""
    from simmer.world import Simulation

    try:
        return Simulation.from_config(config)
    except ConfigError as exc:
        report_config_error(exc)
        raise typer.Exit(1) from None


def is_tap_run(folder: Path) -> bool:
    """Whether ``folder`` is a tap's run of the real robot (no true pose: ``simmer plot``
    draws its traffic instead of a path); False if its manifest cannot be read here (the
    command's own reading says why)."""
    from simmer.record.runfolder import MANIFEST, read_json
    from simmer.tap.folder import is_tap_folder

    try:
        head = read_json(folder / MANIFEST)  # bounded: the folder is untrusted data
    except (OSError, ValueError):
        return False
    return is_tap_folder(head)


def refuse_tap_folder(folder: Path, doing: str) -> None:
    """One plain line and exit status 1 if ``folder`` is a tap's run of the real robot, which
    has no pose to ``doing``: ``simmer plot`` draws what it recorded, over time."""
    if is_tap_run(folder):
        err.print(
            f"{folder} is a tap's run of the real robot: it has no pose to {doing}; "
            f"simmer plot {folder} draws its commands and readings over time (timeline.png), "
            f"simmer compare {folder} --config CONFIG against the simulator's",
            style="bold red",
            markup=False,
        )
        raise typer.Exit(1)
