"""A project sweep's summary speaks of the project (issue 31, item 5): score, delivery rate
and delivery time, its own pictures (not Lab 1's Task 2 time), and its own words for how a
run ended (a run that scored 10 did not "finish without reaching the block")."""

from __future__ import annotations

import csv
import shutil
import statistics
from pathlib import Path

import pygame
import pytest

from simmer.sweep import failure_kind, sweep_from_dict
from simmer.sweep.pictures import draw_pictures
from simmer.sweep.results import header, write_summary
from simmer.sweep.spec import SweepSpec

from helpers import EXAMPLES, REPO

POLICIES = REPO / "tests" / "fixtures" / "sweep" / "sweep_policies.py"
PROJECT = EXAMPLES / "project.toml"


def test_a_project_runs_failure_is_told_by_its_milestones() -> None:
    base = {"collisions": 0, "reached": False, "picked_up": False, "delivered": False}
    kinds = {
        "no-pickup": {**base, "entered_loading": True},  # scored 10: not "stopped short"
        "not-delivered": {**base, "reached": True, "picked_up": True},
        "wrong-zone": {**base, "picked_up": True, "wrong_zone": "B3"},
        "condition": {**base, "picked_up": True, "delivered": True},
    }
    for kind, fields in kinds.items():
        assert failure_kind("ok", fields, success=False, project=True) == kind
    assert failure_kind("ok", kinds["no-pickup"], success=False) == "stopped-short"  # Lab 1
    assert failure_kind("seconds", kinds["no-pickup"], False, project=True) == "timeout"
    assert failure_kind("ok", {**base, "collisions": 1}, False, project=True) == "collision"


def project_spec(folder: Path) -> SweepSpec:
    shutil.copy(POLICIES, folder)
    shutil.copy(PROJECT, folder / "project.toml")
    data = {
        "config": "project.toml",
        "policy": "sweep_policies:drive_and_stop",
        "seeds": 3,
        "success": "delivered and collisions == 0",
        "grid": {"scenario.target": ["B1", "B2"]},
    }
    return sweep_from_dict(data, folder)


RUNS = [  # target, seed, score, milestones met (with their times), failure
    ("B1", 0, 100.0, {"entered_loading": 9.2, "picked_up": 28.2, "left_loading": 34.3,
                      "delivered": 47.9}, ""),
    ("B1", 1, 100.0, {"entered_loading": 9.2, "picked_up": 18.6, "left_loading": 23.3,
                      "delivered": 36.9}, ""),
    ("B1", 2, 10.0, {"entered_loading": 9.2}, "no-pickup"),
    ("B2", 0, 40.0, {"entered_loading": 9.2, "picked_up": 20.0, "left_loading": 26.0},
     "not-delivered"),
    ("B2", 1, 100.0, {"entered_loading": 9.2, "picked_up": 21.0, "left_loading": 27.0,
                      "delivered": 52.5}, ""),
    ("B2", 2, 0.0, {}, "no-pickup"),
]  # fmt: skip


def write_results(folder: Path, spec: SweepSpec) -> list[dict[str, str]]:
    """A project sweep's results.csv as a sweep writes it, its runs as :data:`RUNS` says."""
    columns = header(spec)
    rows = []
    for target, seed, score, met, failure in RUNS:
        cells = dict.fromkeys(columns, "")
        cells.update(
            {"scenario.target": target, "seed": str(seed), "success": str(not failure),
             "failure": failure, "time": "60.0", "first_motion": "0.0", "collisions": "0",
             "reached": str("picked_up" in met), "final_x": "66.0", "final_y": "9.0",
             "final_heading": "180.0", "target": target, "start_x": "6.0", "start_y": "42.0",
             "block_x": "18.0", "block_y": "18.0", "score": repr(score), "status": "ok",
             "exit_status": "0", "wall_time": "1.0", "run": f"{target}{seed}", "detail": ""}
        )  # fmt: skip
        for name in ("entered_loading", "picked_up", "left_loading", "delivered"):
            cells[name] = str(name in met)
            cells[f"{name}_at"] = repr(met[name]) if name in met else ""
        rows.append(cells)
    with (folder / "results.csv").open("w", encoding="utf-8", newline="") as file:
        writer = csv.DictWriter(file, columns)
        writer.writeheader()
        writer.writerows(rows)
    return rows


@pytest.mark.slow  # draws six pictures: some 3 CPU seconds
def test_a_project_sweeps_summary_gives_score_delivery_and_its_own_pictures(
    tmp_path: Path,
) -> None:
    spec = project_spec(tmp_path)
    assert spec.project
    write_results(tmp_path, spec)
    summary = write_summary(tmp_path, spec, "sweep.toml", draw_pictures).read_text("utf-8")
    scores = [score for _, _, score, _, _ in RUNS]
    mean, spread = statistics.fmean(scores), statistics.stdev(scores)
    said = f"of the 6 runs with one): mean {mean:.1f} ± {spread:.1f} (median 70, from 0 to 100)"
    assert said in summary
    assert "Delivered to the target in 3/6 = 50%" in summary
    times = [met["delivered"] for *_, met, _ in RUNS if "delivered" in met]
    assert f"median {statistics.median(times):.1f} s" in summary
    assert f"from {min(times):.1f} to {max(times):.1f} s" in summary
    assert "| B1 | 3 | 2 | 67% | " in summary
    b1 = [s for t, _, s, _, _ in RUNS if t == "B1"]
    assert f"| {statistics.fmean(b1):.1f} ({statistics.stdev(b1):.1f}) | 2/3 | 42.4 s |" in summary
    # its own words for how a run ended: the run that scored 10 did not "stop short"
    assert "stopped-short" not in summary
    assert "without reaching the block" not in summary
    assert "### No pickup: finished without picking up the block (2)" in summary
    assert "### Not delivered: picked up the block but finished without delivering it (1)" in (
        summary
    )
    assert "score 10" in summary
    assert "score 40" in summary
    assert "Task 2" not in summary
    # its own pictures: the score and the delivery time, not Lab 1's Task 2 time
    assert not (tmp_path / "task2_time.png").exists()
    assert "](start_cells.png)" in summary
    for name in ("score.png", "delivery_time.png"):
        assert f"]({name})" in summary
        picture = pygame.image.load(str(tmp_path / name))
        assert picture.get_width() > 300
        pixels = pygame.surfarray.array3d(picture).reshape(-1, 3).astype(int)
        r, g, b = pixels.T
        assert ((b > r + 60) & (b > g + 20)).sum() > 500, f"{name}: no bars drawn"
