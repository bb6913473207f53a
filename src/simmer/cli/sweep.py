"""``simmer sweep``: a program run over seeds and settings in parallel."""

from __future__ import annotations

from enum import StrEnum
from pathlib import Path
from typing import Annotated

import typer

from simmer.cli.app import Command, app, err, example, out
from simmer.cli.common import number_check

MAX_WORKERS = 64
"""Largest ``sweep --workers``: each worker process holds some 256 MB, so 64 of them hold
16 GB, more than a lab machine has, and more workers than cores only wait their turn (a pool
of 10**6 would start a process for each run of a sweep, up to 100,000)."""


class Engine(StrEnum):
    """Choices of ``simmer sweep --engine``."""

    local = "local"
    dask = "dask"


@app.command(
    cls=Command,
    short_help="Run a program over seeds and settings: success rates.",
    epilog=example("simmer sweep sweep_dead_reckoning.toml --workers 2"),
)
def sweep(
    sweep_file: Annotated[Path, typer.Argument(help="Sweep file (.toml).", metavar="SWEEP")],
    output: Annotated[
        Path | None,
        typer.Option(
            "-o",
            "--output",
            help="Folder for results.csv and summary.md (default: SWEEP-results in the current "
            "folder, SWEEP being the sweep file's name without .toml).",
            show_default=False,
            metavar="DIR",
        ),
    ] = None,
    workers: Annotated[
        int | None,
        typer.Option(
            help="Worker processes (default: one per core).",
            callback=number_check(
                "--workers", "workers", MAX_WORKERS, "MAX_WORKERS", zero=True, low=1
            ),
            show_default=False,
            metavar="N",
        ),
    ] = None,
    resume: Annotated[
        bool,
        typer.Option("--resume", help="Keep the runs already in results.csv; run only the others."),
    ] = False,
    engine: Annotated[
        Engine,
        typer.Option(help="Where runs go: local processes or Dask.", metavar="local|dask"),
    ] = Engine.local,
    address: Annotated[
        str | None,
        typer.Option(
            help="Dask scheduler (tcp://host:8786); none: a local Dask cluster.",
            metavar="ADDRESS",
        ),
    ] = None,
) -> None:
    """Run a controller over seeds and settings in parallel: results.csv (a row per run) and
    summary.md (success rate per setting with 95% intervals)."""
    from simmer.errors import SweepError, UnsafeOutput
    from simmer.sweep import dask_engine, load_sweep, local_pool, run_sweep

    try:
        spec = load_sweep(sweep_file)
        chosen = dask_engine(address, workers) if engine is Engine.dask else local_pool(workers)
    except (SweepError, RuntimeError) as exc:
        err.print(str(exc), style="bold red", markup=False)
        raise typer.Exit(1) from None
    folder = output or Path(f"{sweep_file.stem}-results")  # the student's folder, not the file's
    try:
        done = run_sweep(
            spec,
            folder,
            engine=chosen,
            workers=workers,
            resume=resume,
            console=err,
            source=sweep_file.name,
        )
    except SweepError as exc:  # a setting no run could use: found before any run
        err.print(f"{sweep_file}: {exc}", style="bold red", markup=False)
        raise typer.Exit(1) from None
    except (FileExistsError, ValueError, UnsafeOutput) as exc:  # a link where it writes
        err.print(str(exc), style="bold red", markup=False)
        raise typer.Exit(1) from None
    except KeyboardInterrupt as exc:
        import signal

        signum = getattr(exc, "signum", signal.SIGINT)
        err.print(
            f"stopped ({signal.Signals(signum).name}); the workers and their programs are "
            f"stopped; finished runs are in {folder / 'results.csv'} (--resume goes on)",
            markup=False,
        )
        raise typer.Exit(128 + signum) from None
    out.print(
        f"{done.successes}/{done.runs} succeeded ({done.ran} run now, {done.wall_time:.1f} s); "
        f"wrote {folder / 'results.csv'} and {folder / 'summary.md'}",
        markup=False,
    )
