"""Running a grading: every team's program in every scenario, on the sweep's engine (a local
process pool or Dask), each in its box; then the leaderboard, the reports, the violation
log, a thumbnail per team and the failure videos."""

from __future__ import annotations

import time
from dataclasses import dataclass, replace
from pathlib import Path
from typing import TYPE_CHECKING

from simmer.ending import RunEnd
from simmer.grade.board import Standing, write_board
from simmer.grade.spec import GradeSpec
from simmer.sweep.engine import Engine, Pool, Table, execute_all, run_table, to_film
from simmer.sweep.results import read_rows
from simmer.sweep.runs import RunResult, RunSpec, film
from simmer.sweep.success import OUTCOME_FIELDS, PROJECT_FIELDS

if TYPE_CHECKING:
    from rich.console import Console

__all__ = ["GradeResult", "grade_columns", "run_grading"]

STOPPED_AT_LIMIT = frozenset({RunEnd.SECONDS, RunEnd.TIMEOUT})
"""Ends of a run whose output tail a grading does not keep: the program was stopped, and
what it printed as it was (a traceback of the closed link, or nothing) depends on timing, so
the same grading would not give the same table."""
TAIL = ("status", "exit_status", "wall_time", "run", "folder", "detail")


@dataclass(frozen=True)
class GradeResult:
    """What :func:`run_grading` did."""

    folder: Path
    runs: int
    ran: int
    standings: list[Standing]
    wall_time: float
    filmed: int = 0
    notes: tuple[str, ...] = ()
    """What the box could not enforce on this machine, a line each (also in leaderboard.md)."""


def grade_columns(spec: GradeSpec) -> list[str]:
    """results.csv's columns: the team and scenario, seed, success, how it failed, the
    outcome (and the project's fields), then the run's own."""
    project = PROJECT_FIELDS if spec.project else ()
    return [*spec.columns, "seed", "success", "failure", *OUTCOME_FIELDS, *project, *TAIL]


def run_grading(
    spec: GradeSpec,
    folder: Path,
    *,
    engine: Engine | None = None,
    workers: int | None = None,
    resume: bool = False,
    console: Console | None = None,
    source: str = "",
) -> GradeResult:
    """Run every run of ``spec`` not yet in ``folder``/results.csv (``resume``), each row
    appended as it finishes and each run's folder kept under ``runs/``; then put the table in
    the grading's order, film each team's first failures and write the leaderboard."""
    started = time.perf_counter()
    notes = box_notes(spec)
    runs = spec.runs()
    ran, _successes, filmed = run_table(
        runs,
        Table(folder, grade_columns(spec), spec.folder_names(), spec.project, _untimed),
        lambda pool: _film(spec, runs, folder, pool),
        engine=engine,
        workers=workers,
        resume=resume,
        progress=(console, "grading", False),
    )
    rows = read_rows(folder / "results.csv")
    thumbnails = _thumbnails(spec, folder, rows)
    table = write_board(folder, spec, rows, source, thumbnails, notes)
    wall = time.perf_counter() - started
    return GradeResult(folder, len(runs), ran, table, wall, filmed, notes)


def box_notes(spec: GradeSpec) -> tuple[str, ...]:
    """A line for each part of the box asked for that this machine cannot give (the runs go
    on without it): so far, a network of the program's own."""
    from simmer.lockstep.netns import unavailable

    why = unavailable() if spec.limits.network else ""
    if not why:
        return ()
    return (
        f"the box: no network of its own for each program here ({why}); programs share this "
        "machine's network (Landlock's TCP port rules still apply where the kernel has them; "
        "[limits] network = false says this on purpose)",
    )


def _untimed(result: RunResult) -> RunResult:
    """A result without what its program printed as it was stopped at a limit (it depends on
    timing: the same grading would not give the same table)."""
    return replace(result, detail="") if result.status in STOPPED_AT_LIMIT else result


def _film(spec: GradeSpec, runs: list[RunSpec], folder: Path, pool: Pool) -> int:
    """Film each team's first ``spec.videos`` failures that have a folder and no video yet."""
    if not spec.videos:
        return 0
    by_key = {r["run"]: r for r in read_rows(folder / "results.csv")}
    todo = [
        run
        for team in spec.teams
        for run in to_film([r for r in runs if r.team == team.name], by_key, folder, spec.videos)
    ]

    def record(run: RunSpec, result: RunResult) -> None:
        if "video.mp4" in result.files:
            from simmer.record.safefile import write_bytes

            write_bytes(
                folder / by_key[run.key()]["folder"] / "video.mp4", result.files["video.mp4"]
            )

    execute_all(todo, pool, film, record)
    return len(todo)


def _thumbnails(spec: GradeSpec, folder: Path, rows: list[dict[str, str]]) -> dict[str, str]:
    """A picture of each team's first kept run's path (``teams/TEAM.png``), by team name;
    a run that cannot be drawn has none."""
    from simmer.record.plots import read_run, write_path_plot

    (folder / "teams").mkdir(exist_ok=True)
    pictures = {}
    for team in spec.teams:
        kept = next((r["folder"] for r in rows if r["team"] == team.name and r["folder"]), "")
        target = folder / "teams" / f"{team.slug}.png"
        if not kept:
            continue
        try:
            write_path_plot(read_run(folder / kept), target)
        except (OSError, ValueError):
            continue
        pictures[team.name] = f"teams/{team.slug}.png"
    return pictures
