"""Sweeps (issue 12): a controller over seeds and settings in parallel, isolated, reproducible
and resumable, with a results table and a summary."""

from __future__ import annotations

import csv
import shutil
import sys
from pathlib import Path
from typing import Any

import pytest
from typer.testing import CliRunner

from simmer.cli import app
from simmer.sweep import (
    SweepError,
    SweepSpec,
    apply_overrides,
    build_config,
    load_sweep,
    run_sweep,
    success_condition,
    sweep_from_dict,
    wilson_interval,
)
from simmer.sweep.spec import OUTCOME_FIELDS

from helpers import EXAMPLES, REPO, SIMMER_PY

pytestmark = pytest.mark.timeout(300)

POLICIES = REPO / "tests" / "fixtures" / "sweep" / "sweep_policies.py"
LAB1 = EXAMPLES / "lab1_rover.toml"
NOISE = "drives.w0.error.y"


def policy_sweep(folder: Path, policy: str, **more: Any) -> SweepSpec:
    """A sweep of a test policy (copied into ``folder``, the sweep file's folder)."""
    shutil.copy(POLICIES, folder)
    data = {"config": str(LAB1), "policy": f"sweep_policies:{policy}", **more}
    return sweep_from_dict(data, folder)


def read_table(path: Path) -> list[dict[str, str]]:
    with path.open(encoding="utf-8", newline="") as file:
        return list(csv.DictReader(file))


def without_wall_time(rows: list[dict[str, str]]) -> list[dict[str, str]]:
    return [{k: v for k, v in row.items() if k != "wall_time"} for row in rows]


# ----------------------------------------------------------------------------- pieces


def test_wilson_interval_matches_known_values() -> None:
    assert wilson_interval(8, 10) == pytest.approx((0.4902, 0.9433), abs=5e-4)
    assert wilson_interval(0, 10) == pytest.approx((0.0, 0.2775), abs=5e-4)
    assert wilson_interval(10, 10) == pytest.approx((0.7225, 1.0), abs=5e-4)
    assert wilson_interval(50, 100) == pytest.approx((0.4038, 0.5962), abs=5e-4)
    assert wilson_interval(0, 0) == (0.0, 1.0)


def test_overrides_set_dotted_keys_and_make_missing_tables() -> None:
    data: dict[str, Any] = {"drives": {"w0": {"velocity": [0, 6]}}, "frame_rate": 60}
    apply_overrides(data, ((NOISE, 0.1), ("frame_rate", 30), ("drives.w0.velocity", [0, 3])))
    assert data == {"drives": {"w0": {"velocity": [0, 3], "error": {"y": 0.1}}}, "frame_rate": 30}
    with pytest.raises(KeyError, match="frame_rate is a value"):
        apply_overrides(data, (("frame_rate.x", 1),))


def test_a_broken_configuration_file_is_named_with_its_line(tmp_path: Path) -> None:
    from simmer.errors import ConfigError

    broken = tmp_path / "robot.toml"
    broken.write_text("frame_rate = 60\nframe_rate = 30\n", encoding="utf-8")
    with pytest.raises(ConfigError) as caught:
        build_config(str(broken), ())
    (issue,) = caught.value.issues
    assert issue.line == 2
    assert "set twice" in issue.message


@pytest.mark.parametrize("path", [LAB1, SIMMER_PY / "default_config.py"])
def test_build_config_overrides_toml_and_config_py(path: Path) -> None:
    plain = build_config(str(path), ())
    noisy = build_config(str(path), ((NOISE, 0.05), ("sensors.u0.error", 0.3)))
    assert plain.device("w0").params.error.y == 0  # type: ignore[attr-defined]
    assert noisy.device("w0").params.error.y == 0.05  # type: ignore[attr-defined]
    assert noisy.device("u0").params.error == 0.3  # type: ignore[attr-defined]
    assert noisy.settings == plain.settings


def test_an_override_that_does_not_validate_is_an_invalid_run(tmp_path: Path) -> None:
    spec = policy_sweep(tmp_path, "drive_and_stop", grid={NOISE: ["lots"]})
    run_sweep(spec, tmp_path / "out", workers=1)
    (row,) = read_table(tmp_path / "out" / "results.csv")
    assert row["status"] == "invalid"
    assert "drives.w0.error.y" in row["detail"]
    assert row["success"] == "False"


def test_success_condition_uses_outcome_fields_only() -> None:
    fields = {"reached": True, "collisions": 0, "task2_time": 23.0, "final_x": 66.0}
    assert success_condition("reached and collisions == 0")(fields)
    assert success_condition("task2_time < 30 and not collisions > 0")(fields)
    assert not success_condition("task2_time * 2 < 30")(fields)
    assert success_condition("60 < final_x <= 70 or false")(fields)
    assert not success_condition("first_collision < 5")(fields)  # no value: false
    for text in ("__import__('os')", "reached.real", "path", "[1][0]", "reached if 1 else 0"):
        with pytest.raises(SweepError, match="success"):
            success_condition(text)


def test_sweep_file_mistakes_are_named(tmp_path: Path) -> None:
    good = {"config": str(LAB1), "program": "python robot.py"}
    mistakes = [
        ({"config": str(LAB1)}, "name one controller"),
        ({**good, "policy": "a:b"}, "name one controller"),
        ({**good, "seeds": 0}, "seeds"),
        ({**good, "seeds": [1, 1]}, "seeds"),
        ({**good, "grid": {NOISE: []}}, "non-empty list"),
        ({**good, "wall_seconds": -1}, "wall_seconds"),
        ({**good, "config": "nowhere.toml"}, "no such file"),
        ({**good, "success": "import os"}, "success"),
        ({**good, "sedes": 3}, "unknown key"),
        ({"config": str(LAB1), "policy": "no colon"}, "module:function"),
    ]
    for data, message in mistakes:
        with pytest.raises(SweepError, match=message):
            sweep_from_dict(data, tmp_path)


def test_runs_are_listed_in_order_with_stable_keys(tmp_path: Path) -> None:
    spec = policy_sweep(tmp_path, "drive_and_stop", seeds=[5, 7], grid={NOISE: [0.0, 0.1]})
    runs = spec.runs()
    assert [(run.setting, run.seed) for run in runs] == [
        ((0.0,), 5), ((0.0,), 7), ((0.1,), 5), ((0.1,), 7),
    ]  # fmt: skip
    assert len({run.key() for run in runs}) == 4
    assert [run.key() for run in runs] == [run.key() for run in spec.runs()]


# ----------------------------------------------------------------------------- sweeps


def test_policy_sweep_is_parallel_reproducible_and_resumable(tmp_path: Path) -> None:
    spec = policy_sweep(tmp_path, "drive_and_stop", seeds=3, grid={NOISE: [0.0, 0.1]})
    first = run_sweep(spec, tmp_path / "a", workers=2)
    assert (first.runs, first.ran) == (6, 6)
    rows = read_table(tmp_path / "a" / "results.csv")
    assert list(rows[0]) == [
        NOISE, "seed", "success", *OUTCOME_FIELDS,
        "status", "exit_status", "wall_time", "run", "detail",
    ]  # fmt: skip
    assert [(row[NOISE], row["seed"]) for row in rows] == [
        (noise, seed) for noise in ("0.0", "0.1") for seed in "012"
    ]
    assert {row["status"] for row in rows} == {"ok"}
    quiet = {row["final_y"] for row in rows if row[NOISE] == "0.0"}
    noisy = {row["final_y"] for row in rows if row[NOISE] == "0.1"}
    assert len(quiet) == 1  # no noise: every seed the same
    assert len(noisy) == 3  # noise: each seed its own
    assert all(float(row["path_length"]) > 10 for row in rows)

    again = run_sweep(spec, tmp_path / "b", workers=1)
    assert again.ran == 6
    assert without_wall_time(read_table(tmp_path / "b" / "results.csv")) == without_wall_time(rows)

    before = (tmp_path / "a" / "results.csv").read_text(encoding="utf-8")
    resumed = run_sweep(spec, tmp_path / "a", workers=2, resume=True)
    assert resumed.ran == 0
    assert (tmp_path / "a" / "results.csv").read_text(encoding="utf-8") == before
    with pytest.raises(FileExistsError, match="--resume"):
        run_sweep(spec, tmp_path / "a", workers=2)
    summary = (tmp_path / "a" / "summary.md").read_text(encoding="utf-8")
    assert "| 0.0 | 3 | 0 | 0% | 0.000 to 0.561 | ok 3 |" in summary
    assert (tmp_path / "a" / "success_rate.png").stat().st_size > 1000
    assert (tmp_path / "a" / "final_positions.png").stat().st_size > 1000


def test_resume_runs_only_what_is_missing(tmp_path: Path) -> None:
    spec = policy_sweep(tmp_path, "drive_and_stop", seeds=2, grid={NOISE: [0.0, 0.1]})
    run_sweep(spec, tmp_path / "out", workers=2)
    table = tmp_path / "out" / "results.csv"
    full = table.read_text(encoding="utf-8").splitlines()
    table.write_text("\n".join(full[:3]) + "\n", encoding="utf-8")  # as if stopped after two
    resumed = run_sweep(spec, tmp_path / "out", workers=2, resume=True)
    assert resumed.ran == 2
    assert without_wall_time(read_table(table)) == without_wall_time(list(csv.DictReader(full)))


def test_failing_policies_are_recorded_and_the_sweep_finishes(tmp_path: Path) -> None:
    cases = {
        "crash": ("error", "this policy always fails", {}),
        "spin_forever": ("timeout", "", {"wall_seconds": 1}),
        "sleep_forever": ("seconds", "", {"seconds": 5}),
        "kill_worker": ("crashed", "worker process died", {}),
    }
    for policy, (status, detail, limits) in cases.items():
        spec = policy_sweep(tmp_path, policy, seeds=2, **limits)
        done = run_sweep(spec, tmp_path / policy, workers=2)
        rows = read_table(tmp_path / policy / "results.csv")
        assert done.ran == 2
        assert [row["status"] for row in rows] == [status, status], policy
        assert all(detail in row["detail"] for row in rows), rows
        assert all(row["success"] == "False" for row in rows)
    assert "**error**" in (tmp_path / "crash" / "summary.md").read_text(encoding="utf-8")
    slept = read_table(tmp_path / "sleep_forever" / "results.csv")
    assert float(slept[0]["time"]) == pytest.approx(5.0, abs=0.1)


def test_a_hanging_program_is_stopped_at_the_wall_limit(tmp_path: Path) -> None:
    command = f'"{sys.executable}" -c "print(chr(0) * 50, flush=True)\nwhile True: pass"'
    spec = sweep_from_dict(
        {"config": str(LAB1), "program": command, "seeds": 2, "wall_seconds": 1.5}, tmp_path
    )
    done = run_sweep(spec, tmp_path / "out", workers=2)
    rows = read_table(tmp_path / "out" / "results.csv")
    assert done.ran == 2
    assert [row["status"] for row in rows] == ["timeout", "timeout"]
    assert all(1.4 < float(row["wall_time"]) < 10 for row in rows)


def test_minimal_sweep_file_through_the_cli(tmp_path: Path) -> None:
    shutil.copy(SIMMER_PY / "lab_rover_quiet.py", tmp_path / "config.py")
    shutil.copy(EXAMPLES / "dead_reckoning.py", tmp_path)
    (tmp_path / "sweep.toml").write_text(
        'config = "config.py"\n'
        f"program = '\"{sys.executable}\" -u dead_reckoning.py'\n"
        "seeds = 2\n\n[grid]\n"
        '"drives.w0.error.y" = [0.0, 0.05]\n',
        encoding="utf-8",
    )
    result = CliRunner().invoke(
        app, ["sweep", str(tmp_path / "sweep.toml"), "-o", str(tmp_path / "out"), "--workers", "2"]
    )
    assert result.exit_code == 0, result.output
    assert "succeeded" in result.output
    rows = read_table(tmp_path / "out" / "results.csv")
    assert [(row[NOISE], row["seed"], row["status"]) for row in rows] == [
        ("0.0", "0", "ok"), ("0.0", "1", "ok"), ("0.05", "0", "ok"), ("0.05", "1", "ok"),
    ]  # fmt: skip
    assert [row["success"] for row in rows[:2]] == ["True", "True"]
    assert all(row["exit_status"] == "0" for row in rows)
    assert float(rows[0]["task2_time"]) == pytest.approx(23.05, rel=0.10)
    summary = (tmp_path / "out" / "summary.md").read_text(encoding="utf-8")
    assert "| 0.0 | 2 | 2 | 100% | 0.342 to 1.000 | ok 2 |" in summary
    again = CliRunner().invoke(
        app, ["sweep", str(tmp_path / "sweep.toml"), "-o", str(tmp_path / "out"), "--resume"]
    )
    assert again.exit_code == 0, again.output
    assert "0 run now" in again.output


def test_the_example_sweep_file_loads() -> None:
    spec = load_sweep(EXAMPLES / "sweep_dead_reckoning.toml")
    assert spec.kind == "program"
    assert len(spec.runs()) == 30
    assert spec.configs == (LAB1.resolve(),)
