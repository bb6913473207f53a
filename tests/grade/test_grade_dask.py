"""A grading on Dask gives the same tables as on one local worker (issue 35: "the same file
with the same programs gives the same table on 1 or N workers and on Dask")."""

from __future__ import annotations

import csv
from pathlib import Path

import pytest

from grade_support import grading_folder, programs
from simmer.grade import load_grading, run_grading
from simmer.sweep import dask_engine, local_pool


def _rows(path: Path) -> list[dict[str, str]]:
    with path.open(encoding="utf-8", newline="") as file:
        return [{k: v for k, v in r.items() if k != "wall_time"} for r in csv.DictReader(file)]


@pytest.mark.slow
@pytest.mark.timeout(900)  # 8 program runs and a two-worker cluster, on 2 busy cores
def test_a_grading_on_dask_gives_the_local_tables(tmp_path: Path) -> None:
    teams = {name: program for name, program in programs().items() if name in ("Good", "Crash")}
    spec = load_grading(grading_folder(tmp_path / "course", teams=teams))
    local = run_grading(spec, tmp_path / "local", engine=local_pool(1), workers=1, source="G")
    dask = run_grading(spec, tmp_path / "dask", engine=dask_engine(None, 2), workers=2, source="G")
    assert [s.team.name for s in local.standings] == ["Good", "Crash"]
    assert [s.team.name for s in dask.standings] == ["Good", "Crash"]
    for name in ("leaderboard.csv", "leaderboard.md", "violations.csv"):
        assert (tmp_path / "dask" / name).read_bytes() == (tmp_path / "local" / name).read_bytes()
    assert _rows(tmp_path / "dask" / "results.csv") == _rows(tmp_path / "local" / "results.csv")
