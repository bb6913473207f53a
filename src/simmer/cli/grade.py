"""``simmer grade``: several teams' programs over the same scenarios, boxed, on a leaderboard."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from simmer.cli.app import Command, app, err, example, out
from simmer.cli.common import number_check
from simmer.cli.sweep import MAX_WORKERS, Engine


@app.command(
    cls=Command,
    short_help="Run many teams' programs on the same scenarios: a leaderboard.",
    epilog=example("simmer grade GRADING.toml --workers 2   # or, a student: --only ."),
)
def grade(
    grading_file: Annotated[Path, typer.Argument(help="Grading file (.toml).", metavar="GRADING")],
    only: Annotated[
        Path | None,
        typer.Option(
            help="Grade only the team whose folder this is (a student: --only .).",
            show_default=False,
            metavar="FOLDER",
        ),
    ] = None,
    output: Annotated[
        Path | None,
        typer.Option(
            "-o",
            "--output",
            help="Folder for the leaderboard and reports (default: GRADING-results here).",
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
        typer.Option(help="Dask scheduler (tcp://host:8786).", metavar="ADDRESS"),
    ] = None,
) -> None:
    """Run every team's program in every scenario of a grading file, each in its box:
    leaderboard.csv, leaderboard.md, index.html, a report per team and violations.csv."""
    from simmer.errors import SweepError, UnsafeOutput
    from simmer.grade import load_grading, run_grading
    from simmer.sweep import dask_engine, local_pool

    try:
        spec = load_grading(grading_file)
        if only is not None:
            spec = spec.only(only)
        chosen = dask_engine(address, workers) if engine is Engine.dask else local_pool(workers)
    except (SweepError, RuntimeError) as exc:
        err.print(str(exc), style="bold red", markup=False)
        raise typer.Exit(1) from None
    folder = output or Path(f"{grading_file.stem}-results")
    try:
        done = run_grading(
            spec,
            folder,
            engine=chosen,
            workers=workers,
            resume=resume,
            console=err,
            source=grading_file.name,
        )
    except (FileExistsError, ValueError, UnsafeOutput) as exc:
        err.print(str(exc), style="bold red", markup=False)
        raise typer.Exit(1) from None
    except KeyboardInterrupt as exc:
        import signal

        signum = getattr(exc, "signum", signal.SIGINT)
        err.print(
            f"stopped ({signal.Signals(signum).name}); finished runs are in "
            f"{folder / 'results.csv'} (--resume goes on)",
            markup=False,
        )
        raise typer.Exit(128 + signum) from None
    for note in done.notes:
        err.print(note, markup=False)
    for rank, standing in enumerate(done.standings, 1):
        score = f"score {standing.score:.1f}, " if standing.score is not None else ""
        out.print(
            f"{rank}. {standing.team.name}: {score}{standing.successes}/{standing.runs} "
            f"succeeded, {standing.violations} violation(s)",
            markup=False,
        )
    out.print(
        f"{done.ran} run(s) now, {done.wall_time:.1f} s; wrote {folder / 'leaderboard.md'} "
        f"and {folder / 'index.html'}",
        markup=False,
    )
