"""Grading benchmark: program runs per second per worker of ``simmer grade`` against a sweep's,
on the same program and the same scenarios, and what a whole grading costs on 1 and 2 workers.

Run ``python benchmarks/bench_grade.py`` (or ``python benchmarks/run.py`` for every benchmark).
The program is the course project's example, ``examples/project_delivery.py`` (plain two-port
sockets, told its target at an ``input()`` prompt), on ``examples/project.toml`` over the four
target zones and two seeds. A sweep run keeps nothing; a grading run is the same run in a box
(its own copy of the team's folder, rlimits, Landlock where the kernel has it, a network
namespace of its own where the machine allows it, its own user as root) and keeps its whole
folder (the replay the page links); the same boxed without the network namespace gives the
namespace's cost. Per-worker figures run in this
process one run after another after a warm-up run; whole gradings go through the process pool
and include its start-up, the leaderboard, the reports and a thumbnail per team.
"""

from __future__ import annotations

import os
import shutil
import sys
import tempfile
import time
from dataclasses import replace
from pathlib import Path
from typing import Any

from simmer.grade import run_grading
from simmer.grade.spec import grade_from_dict
from simmer.sweep import local_pool
from simmer.sweep.runs import RunSpec, execute
from simmer.sweep.spec import sweep_from_dict

ROOT = Path(__file__).resolve().parent.parent
EXAMPLES = ROOT / "examples"
PYTHON = "/usr/bin/python3" if os.name == "posix" and os.getuid() == 0 else sys.executable
"""As root a box runs as a user of its own, who may not read root's home (a venv there)."""
PROGRAM = f'"{PYTHON}" -u robot.py'
TARGETS = ["B1", "B2", "B3", "B4"]
SEEDS = [1, 2]
COMMON: dict[str, Any] = {
    "config": "project.toml",
    "answer": "{target}",
    "seconds": 300,
    "wall_seconds": 60,
    "success": "delivered and collisions == 0",
}


def course(folder: Path, teams: int) -> Path:
    """A course folder: project.toml and ``teams`` team folders, each with the example program
    as robot.py; the folder."""
    folder.mkdir(parents=True, exist_ok=True)
    shutil.copy(EXAMPLES / "project.toml", folder / "project.toml")
    program = (EXAMPLES / "project_delivery.py").read_text(encoding="utf-8")
    for number in range(1, teams + 1):
        (folder / "teams" / f"t{number}").mkdir(parents=True, exist_ok=True)
        (folder / "teams" / f"t{number}" / "robot.py").write_text(program, encoding="utf-8")
    return folder


def grading_runs(folder: Path, teams: int) -> Any:
    """The grading of ``teams`` teams of the example program over every target and seed."""
    data = {
        **COMMON,
        "scenarios": {"seeds": SEEDS, "scenario.target": TARGETS},
        "team": [
            {"name": f"Team {n}", "folder": f"teams/t{n}", "program": PROGRAM}
            for n in range(1, teams + 1)
        ],
    }
    return grade_from_dict(data, folder)


def sweep_runs(folder: Path) -> list[RunSpec]:
    """The sweep of the same program over the same scenarios, from the team's folder."""
    data = {
        **COMMON,
        "config": str(folder / "project.toml"),
        "program": PROGRAM,
        "seeds": SEEDS,
        "keep": "nothing",
        "grid": {"scenario.target": TARGETS},
    }
    return sweep_from_dict(data, folder / "teams" / "t1").runs()


def runs_per_second(runs: list[RunSpec]) -> float:
    """Runs per second carried out one after another in this process, after a warm-up run
    (the configuration read, the kernels compiled); every run must deliver."""
    execute(runs[0])
    started = time.perf_counter()
    for run in runs:
        result = execute(run)
        if not result.success:
            raise SystemExit(f"a benchmark run ended {result.status}: {result.detail}")
    return len(runs) / (time.perf_counter() - started)


def whole_grading(folder: Path, teams: int, workers: int) -> float:
    """Program runs per second of a whole grading through the process pool."""
    spec = grading_runs(folder, teams)
    out = Path(tempfile.mkdtemp(dir=folder))
    done = run_grading(spec, out, engine=local_pool(workers), workers=workers)
    return done.runs / done.wall_time


def main() -> dict[str, float]:
    """Run the grading benchmark and print its figures and ratios."""
    with tempfile.TemporaryDirectory() as scratch:
        folder = course(Path(scratch) / "course", 2)
        sweep = sweep_runs(folder)
        graded = grading_runs(folder, 1).runs()
        unboxed = [replace(run, box=None) for run in graded]
        shared = [
            replace(run, box=replace(run.box, network=False)) if run.box else run for run in graded
        ]
        figures = {
            "sweep": runs_per_second(sweep),
            "kept": runs_per_second(unboxed),
            "grade": runs_per_second(graded),
            "shared": runs_per_second(shared),
        }
        for workers in (1, 2):
            figures[f"whole_{workers}"] = whole_grading(folder, 2, workers)
    figures["ratio"] = figures["grade"] / figures["sweep"]
    figures["box_ms"] = 1000 / figures["grade"] - 1000 / figures["kept"]
    figures["network_ms"] = 1000 / figures["grade"] - 1000 / figures["shared"]
    figures["speedup"] = figures["whole_2"] / figures["whole_1"]
    runs = len(TARGETS) * len(SEEDS)
    rows = [
        (f"sweep: program runs/s per worker ({runs} runs, keep nothing)", "sweep"),
        ("the same runs kept whole (what a grading keeps), no box", "kept"),
        ("grading: program runs/s per worker (boxed, kept whole)", "grade"),
        ("  grading / sweep", "ratio"),
        ("  the box's cost per run, ms (boxed minus kept)", "box_ms"),
        ("boxed without a network namespace of its own: runs/s per worker", "shared"),
        ("  the network namespace's cost per run, ms", "network_ms"),
        (f"whole grading, 2 teams x {runs} scenarios, 1 worker: runs/s", "whole_1"),
        ("the same, 2 workers: runs/s", "whole_2"),
        ("  speed-up from 1 to 2 workers", "speedup"),
    ]
    print("SimMeR grading benchmark")
    for label, key in rows:
        print(f"  {label:<72} {figures[key]:10.2f}")
    return figures


if __name__ == "__main__":
    main()
