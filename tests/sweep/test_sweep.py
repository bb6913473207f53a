"""Sweeps (issue 12): a controller over seeds and settings in parallel, isolated, reproducible
and resumable, with a results table and a summary."""

from __future__ import annotations

import csv
import os
import shutil
import signal
import subprocess
import sys
import threading
from pathlib import Path
from typing import Any

import pytest
from typer.testing import CliRunner

from simmer.cli import app
from simmer.errors import SweepError
from simmer.record.runfolder import load_run
from simmer.sweep import (
    RunResult,
    RunSpec,
    SweepSpec,
    apply_overrides,
    build_config,
    failure_kind,
    load_sweep,
    run_sweep,
    success_condition,
    sweep_from_dict,
    wilson_interval,
)
from simmer.sweep.runs import execute
from simmer.sweep.spec import OUTCOME_FIELDS
from simmer.world.replay import replay

from helpers import EXAMPLES, REPO, SIMMER_PY, wait_for

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


def test_a_grid_value_or_key_no_run_could_use_stops_the_sweep_before_it_starts(
    tmp_path: Path,
) -> None:
    for grid, words in (
        ({NOISE: [0.0, "lots"]}, "drives.w0.error.y = 'lots'"),
        ({"drives.w0.eror.y": [0.1]}, "did you mean 'error'?"),
    ):
        spec = policy_sweep(tmp_path, "drive_and_stop", grid=grid)
        with pytest.raises(SweepError, match="is not a valid configuration") as caught:
            run_sweep(spec, tmp_path / "out", workers=1)
        assert words in str(caught.value)
        assert not (tmp_path / "out").exists()  # nothing ran, nothing was written


@pytest.mark.slow
def test_a_drawn_value_that_does_not_validate_is_an_invalid_run(tmp_path: Path) -> None:
    sample = {"count": 6, NOISE: {"choice": [0.0, "lots"]}}  # typical (first) value: valid
    spec = policy_sweep(tmp_path, "drive_and_stop", sample=sample)
    run_sweep(spec, tmp_path / "out", workers=1)
    rows = read_table(tmp_path / "out" / "results.csv")
    invalid = [row for row in rows if row[NOISE] == "lots"]
    assert invalid, "the draws include the invalid choice"
    assert all(row["status"] == "invalid" and NOISE in row["detail"] for row in invalid)
    assert all(row["success"] == "False" for row in invalid)
    assert all(row["status"] == "ok" for row in rows if row[NOISE] != "lots")


def test_a_sweep_file_mistake_names_the_file_and_line(tmp_path: Path) -> None:
    sweep = tmp_path / "my_sweep.toml"
    sweep.write_text(f'config = "{LAB1}"\nprogram = "python x.py"\nkeep = "failure"\n')
    with pytest.raises(SweepError, match=r"my_sweep\.toml:3: keep: .*did you mean 'failures'"):
        load_sweep(sweep)


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


def test_a_star_overrides_every_table_at_its_level() -> None:
    data: dict[str, Any] = {"sensors": {"u0": {"error": 0}, "u1": {}}, "frame_rate": 60}
    apply_overrides(data, (("sensors.*.error", 0.02),))
    assert data["sensors"] == {"u0": {"error": 0.02}, "u1": {"error": 0.02}}
    for key in ("motors.*.rotation", "sensors.*", "frame_rate.*.x"):
        with pytest.raises(KeyError, match=r"\*"):
            apply_overrides(data, ((key, 1),))
    config = build_config(str(LAB1), (("sensors.*.error", 0.03),))
    assert {config.device(f"u{i}").params.error for i in range(4)} == {0.03}  # type: ignore[attr-defined]


SAMPLE = {
    "count": 5,
    "sensors.*.error": {"uniform": [0.0, 0.05]},
    "drives.r0.error.rotation": {"normal": [0.01, 0.002]},
    "drives.w0.bias.rotation": {"choice": [0.0, 0.2]},
}


def test_samples_are_drawn_from_the_sample_seed_and_combine_with_the_grid(
    tmp_path: Path,
) -> None:
    spec = policy_sweep(
        tmp_path, "drive_and_stop", seeds=2, grid={NOISE: [0.0, 0.1]}, sample=SAMPLE
    )
    keys = list(SAMPLE)[1:]
    assert spec.columns == (NOISE, "sample", *keys)
    assert spec.setting_columns == (NOISE,)
    runs = spec.runs()
    assert len(runs) == 2 * 5 * 2
    assert len({run.key() for run in runs}) == len(runs)
    draws = spec.draws()
    assert len(draws) == 5
    for uniform, normal, choice in draws:
        assert 0.0 <= uniform <= 0.05
        assert 0.0 < normal < 0.02
        assert choice in (0.0, 0.2)
    # Each grid value gets the same draws; the seed changes fastest.
    assert [run.setting for run in runs[:4]] == [
        (0.0, 0, *draws[0]), (0.0, 0, *draws[0]), (0.0, 1, *draws[1]), (0.0, 1, *draws[1]),
    ]  # fmt: skip
    assert runs[10].setting == (0.1, 0, *draws[0])
    assert runs[0].overrides == ((NOISE, 0.0), *zip(keys, draws[0], strict=True))
    # The same file, the same draws; another sample_seed, others; a key's draws are its own.
    assert policy_sweep(tmp_path, "drive_and_stop", sample=SAMPLE).draws() == draws
    other = policy_sweep(tmp_path, "drive_and_stop", sample=SAMPLE, sample_seed=1).draws()
    assert [d[0] for d in other] != [d[0] for d in draws]
    fewer = {"count": 3, "sensors.*.error": SAMPLE["sensors.*.error"]}
    alone = policy_sweep(tmp_path, "drive_and_stop", sample=fewer).draws()
    assert alone == [(d[0],) for d in draws[:3]]


def test_sample_and_keep_mistakes_are_named(tmp_path: Path) -> None:
    good = {"config": str(LAB1), "program": "python robot.py"}
    uniform = {"uniform": [0, 0.1]}
    mistakes = [
        ({"sample": [1]}, r"\[sample\]: count = 20"),
        ({"sample": {NOISE: uniform}}, "count: how many draws"),
        ({"sample": {"count": 0, NOISE: uniform}}, "count: how many draws"),
        ({"sample": {"count": 2}}, "it names none"),
        ({"sample": {"count": 2, NOISE: [0, 0.1]}}, "one distribution"),
        ({"sample": {"count": 2, NOISE: {"uniform": [0, 1], "normal": [0, 1]}}}, "one distrib"),
        ({"sample": {"count": 2, NOISE: {"unifrom": [0, 1]}}}, "did you mean 'uniform'"),
        ({"sample": {"count": 2, NOISE: {"uniform": [1, 0]}}}, "low <= high"),
        ({"sample": {"count": 2, NOISE: {"uniform": [0]}}}, "two numbers"),
        ({"sample": {"count": 2, NOISE: {"normal": [0, "x"]}}}, "two numbers"),
        ({"sample": {"count": 2, NOISE: {"normal": [0, -1]}}}, "standard deviation"),
        ({"sample": {"count": 2, NOISE: {"choice": []}}}, "non-empty list"),
        ({"sample": {"count": 2, NOISE: uniform}, "grid": {NOISE: [0]}}, "also in \\[grid\\]"),
        ({"sample_seed": 3}, "sample_seed: seeds the"),
        ({"sample": {"count": 2, NOISE: uniform}, "sample_seed": -1}, "sample_seed"),
        ({"keep": "failure"}, "did you mean 'failures'"),
        ({"videos": -1}, "videos"),
        ({"videos": 2, "keep": "nothing"}, "videos: a video goes in its run's folder"),
        ({"grid": {NOISE: [0.0, 0.0]}}, "listed twice"),
        ({"config": [str(LAB1), str(LAB1)]}, "each file once"),
    ]
    for more, message in mistakes:
        with pytest.raises(SweepError, match=message):
            sweep_from_dict({**good, **more}, tmp_path)


def test_dotted_keys_need_no_quotes(tmp_path: Path) -> None:
    """``drives.w0.error.y = [...]`` makes nested tables in TOML: the same key as quoted."""
    sweep = tmp_path / "sweep.toml"
    sweep.write_text(
        f"config = '{LAB1}'\nprogram = 'python robot.py'\n"
        "[grid]\ndrives.w0.error.y = [0, 0.1]\n"
        "[sample]\ncount = 2\nsensors.u0.error = {uniform = [0, 0.1]}\n",
        encoding="utf-8",
    )
    spec = load_sweep(sweep)
    assert spec.columns == (NOISE, "sample", "sensors.u0.error")


def test_run_folders_are_named_by_setting_and_seed(tmp_path: Path) -> None:
    spec = policy_sweep(tmp_path, "drive_and_stop", seeds=2, grid={"sensors.*.error": [0.0, 0.1]})
    names = spec.folder_names(spec.runs())
    assert sorted(names.values()) == [
        "sensors.all.error=0.0_seed0", "sensors.all.error=0.0_seed1",
        "sensors.all.error=0.1_seed0", "sensors.all.error=0.1_seed1",
    ]  # fmt: skip
    sampled = policy_sweep(tmp_path, "drive_and_stop", sample=SAMPLE)
    assert list(sampled.folder_names(sampled.runs()).values())[:2] == [
        "sample0_seed0", "sample1_seed0",
    ]  # fmt: skip
    clash = policy_sweep(tmp_path, "drive_and_stop", grid={"frame_rate": ["a b", "a/b"]})
    runs = clash.runs()
    assert clash.folder_names(runs) == {run.key(): f"{run.key()}_seed0" for run in runs}


def test_failures_are_told_apart() -> None:
    fields = {"collisions": 0, "reached": False}
    assert failure_kind("ok", fields, success=True) == ""
    assert failure_kind("ok", fields, success=False) == "stopped-short"
    assert failure_kind("ok", {**fields, "reached": True}, success=False) == "condition"
    assert failure_kind("seconds", fields, success=False) == "timeout"
    assert failure_kind("timeout", fields, success=False) == "timeout"
    assert failure_kind("seconds", {**fields, "collisions": 2}, success=False) == "collision"
    for status in ("error", "crashed", "invalid"):
        assert failure_kind(status, {**fields, "collisions": 2}, success=False) == "crashed"
    assert failure_kind("ok", {}, success=False) == "crashed"


# ----------------------------------------------------------------------------- sweeps


@pytest.mark.slow
def test_policy_sweep_is_parallel_reproducible_and_resumable(tmp_path: Path) -> None:
    spec = policy_sweep(tmp_path, "drive_and_stop", seeds=3, grid={NOISE: [0.0, 0.1]})
    first = run_sweep(spec, tmp_path / "a", workers=2)
    assert (first.runs, first.ran) == (6, 6)
    rows = read_table(tmp_path / "a" / "results.csv")
    assert list(rows[0]) == [
        NOISE, "seed", "success", "failure", *OUTCOME_FIELDS,
        "status", "exit_status", "wall_time", "run", "folder", "detail",
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
    assert "| 0.0 | 3 | 0 | 0% | 0.000 to 0.561 | stopped-short 3 | ok 3 |" in summary
    assert (tmp_path / "a" / "success_rate.png").stat().st_size > 1000
    assert (tmp_path / "a" / "final_positions.png").stat().st_size > 1000


@pytest.mark.slow
def test_resume_runs_only_what_is_missing(tmp_path: Path) -> None:
    spec = policy_sweep(tmp_path, "drive_and_stop", seeds=2, grid={NOISE: [0.0, 0.1]})
    run_sweep(spec, tmp_path / "out", workers=2)
    table = tmp_path / "out" / "results.csv"
    full = table.read_text(encoding="utf-8").splitlines()
    table.write_text("\n".join(full[:3]) + "\n", encoding="utf-8")  # as if stopped after two
    resumed = run_sweep(spec, tmp_path / "out", workers=2, resume=True)
    assert resumed.ran == 2
    assert without_wall_time(read_table(table)) == without_wall_time(list(csv.DictReader(full)))


@pytest.mark.slow
def test_failing_policies_are_recorded_and_the_sweep_finishes(tmp_path: Path) -> None:
    cases = {
        "crash": ("error", "this policy always fails", {}),
        "spin_forever": ("timeout", "", {"wall_seconds": 1}),
        "sleep_forever": ("seconds", "", {"seconds": 5}),
        "kill_worker": ("crashed", "worker process died", {}),
    }
    for policy, (status, detail, limits) in cases.items():
        spec = policy_sweep(tmp_path, policy, seeds=2, keep="nothing", **limits)
        done = run_sweep(spec, tmp_path / policy, workers=2)
        rows = read_table(tmp_path / policy / "results.csv")
        assert done.ran == 2
        assert [row["status"] for row in rows] == [status, status], policy
        assert all(detail in row["detail"] for row in rows), rows
        assert all(row["success"] == "False" for row in rows)
    crashed = (tmp_path / "crash" / "summary.md").read_text(encoding="utf-8")
    assert "### Crashed: the controller failed" in crashed
    assert "this policy always fails" in crashed
    slept = read_table(tmp_path / "sleep_forever" / "results.csv")
    assert float(slept[0]["time"]) == pytest.approx(5.0, abs=0.1)


@pytest.mark.slow
def test_a_hanging_program_is_stopped_at_the_wall_limit(tmp_path: Path) -> None:
    command = f'"{sys.executable}" -c "print(chr(0) * 50, flush=True)\nwhile True: pass"'
    spec = sweep_from_dict(
        {"config": str(LAB1), "program": command, "seeds": 2, "wall_seconds": 1.5}, tmp_path
    )
    done = run_sweep(spec, tmp_path / "out", workers=2)
    rows = read_table(tmp_path / "out" / "results.csv")
    assert done.ran == 2
    assert [row["status"] for row in rows] == ["timeout", "timeout"]
    assert all(float(row["wall_time"]) > 1.4 for row in rows)  # not before its limit
    # how soon after: benchmarks/bench_limits.py


@pytest.mark.slow
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
    assert "| 0.0 | 2 | 2 | 100% | 0.342 to 1.000 | - | ok 2 |" in summary
    again = CliRunner().invoke(
        app, ["sweep", str(tmp_path / "sweep.toml"), "-o", str(tmp_path / "out"), "--resume"]
    )
    assert again.exit_code == 0, again.output
    assert "0 run now" in again.output


@pytest.mark.parametrize(
    ("name", "runs", "columns"),
    [
        ("sweep_dead_reckoning.toml", 60, (NOISE, "drives.r0.error.rotation")),
        (
            "sweep_obstacle_avoidance.toml",
            108,
            ("drives.w0.error.y", "sample", "drives.w0.bias.rotation", "sensors.*.error"),
        ),
    ],
)
def test_the_example_sweep_files_load(name: str, runs: int, columns: tuple[str, ...]) -> None:
    spec = load_sweep(EXAMPLES / name)
    assert spec.kind == "program"
    assert len(spec.runs()) == runs
    assert spec.columns == columns
    assert spec.configs == (LAB1.resolve(),)
    assert (spec.keep, spec.videos > 0) == ("failures", True)


# ----------------------------------------------------------------------------- what is kept


@pytest.mark.slow
def test_failures_are_kept_with_frames_and_the_first_are_filmed(tmp_path: Path) -> None:
    spec = policy_sweep(
        tmp_path, "drive_and_stop", seeds=3, grid={NOISE: [0.0, 0.1]}, success="reached", videos=2
    )
    done = run_sweep(spec, tmp_path / "out", workers=2)
    assert done.filmed == 2
    out = tmp_path / "out"
    rows = read_table(out / "results.csv")
    assert {row["failure"] for row in rows} == {"stopped-short"}
    names = spec.folder_names(spec.runs())
    assert [row["folder"] for row in rows] == [f"runs/{names[row['run']]}" for row in rows]
    videos = sorted(p.parent.name for p in (out / "runs").glob("*/video.mp4"))
    assert videos == [f"{NOISE}=0.0_seed0", f"{NOISE}=0.0_seed1"]  # the first two, in order
    for row in rows:
        folder = out / row["folder"]
        files = {p.name for p in folder.iterdir()}
        assert {"manifest.json", "events.jsonl", "trace.csv", "report.md", "first.png"} <= files
        assert (folder / "last.png").read_bytes()[:4] == b"\x89PNG"
        replayed = replay(*load_run(folder))  # the kept run is the sweep's run
        assert not replayed.differences
        assert list(replayed.sim.robot.pose) == [
            float(row["final_x"]),
            float(row["final_y"]),
            float(row["final_heading"]),
        ]
    assert (out / "runs" / videos[0] / "video.mp4").stat().st_size > 1000
    summary = (out / "summary.md").read_text(encoding="utf-8")
    assert "### Stopped short: finished without reaching the block (6)" in summary
    first = f"runs/{NOISE}=0.0_seed0"
    assert f'<img src="{first}/first.png"' in summary
    assert f"[video]({first}/video.mp4), [run folder]({first}/)" in summary
    assert "the first 2 failures in the sweep's order have a video" in summary

    again = run_sweep(spec, out, workers=1, resume=True)  # nothing to run, nothing to film
    assert (again.ran, again.filmed) == (0, 0)


@pytest.mark.slow
@pytest.mark.parametrize("keep", ["all", "nothing"])
def test_keep_all_or_nothing(tmp_path: Path, keep: str) -> None:
    spec = policy_sweep(tmp_path, "drive_and_stop", seeds=2, success="path_length > 10", keep=keep)
    run_sweep(spec, tmp_path / "out", workers=1)
    rows = read_table(tmp_path / "out" / "results.csv")
    assert [row["success"] for row in rows] == ["True", "True"]
    if keep == "nothing":
        assert [row["folder"] for row in rows] == ["", ""]
        assert not (tmp_path / "out" / "runs").exists()
    else:
        kept = [tmp_path / "out" / row["folder"] for row in rows]
        assert all((folder / "report.json").exists() for folder in kept)
        assert not any((folder / "first.png").exists() for folder in kept)  # successes


# ----------------------------------------------------------------------------- isolation


@pytest.mark.slow
def test_a_crashing_program_is_recorded_with_its_stderr(tmp_path: Path) -> None:
    command = (
        f'"{sys.executable}" -c "import sys; print(42)\n'
        "sys.stderr.write('Traceback: it went wrong here\\n'); sys.exit(3)\""
    )
    spec = sweep_from_dict(
        {"config": str(LAB1), "program": command, "seeds": 2, "wall_seconds": 20}, tmp_path
    )
    done = run_sweep(spec, tmp_path / "out", workers=2)
    rows = read_table(tmp_path / "out" / "results.csv")
    assert done.ran == 2
    assert [(row["status"], row["exit_status"], row["failure"]) for row in rows] == [
        ("error", "3", "crashed"), ("error", "3", "crashed"),
    ]  # fmt: skip
    assert all("Traceback: it went wrong here" in row["detail"] for row in rows)
    report = (tmp_path / "out" / rows[0]["folder"] / "report.md").read_text(encoding="utf-8")
    assert "the control program exited with status 3" in report
    folder = tmp_path / "out" / rows[0]["folder"]
    assert report.startswith(f"# SimMeR run: {folder.name}\n")  # not the worker's scratch name
    assert f"simmer plot {folder}`" in report
    summary = (tmp_path / "out" / "summary.md").read_text(encoding="utf-8")
    assert "failed (exit status 3)" in summary
    assert "it went wrong here" in summary


def test_the_wall_limit_stops_a_policy_in_a_thread_too(tmp_path: Path) -> None:
    """A Dask worker runs each run in a thread of its own, where SIGALRM cannot reach: the
    run's link ends it at its next message (no exception is sent into the thread from
    outside, so a policy that never asks the simulator anything runs on there)."""
    shutil.copy(POLICIES, tmp_path)
    run = RunSpec(
        str(LAB1), (), 0, "policy", "sweep_policies:sleep_forever", str(tmp_path), None, 0.5
    )
    results: list[RunResult] = []
    thread = threading.Thread(target=lambda: results.append(execute(run)))
    thread.start()
    thread.join(timeout=30)
    assert not thread.is_alive()
    assert results[0].status == "timeout"
    assert results[0].wall_time > 0.4  # not before its limit; how soon after: bench_limits.py


@pytest.mark.slow
@pytest.mark.usefixtures("ctrl_c")
def test_resume_after_ctrl_c_runs_only_the_missing_runs(tmp_path: Path) -> None:
    shutil.copy(POLICIES, tmp_path)
    sweep = tmp_path / "sweep.toml"
    sweep.write_text(
        f"config = '{LAB1}'\npolicy = 'sweep_policies:drive_slowly'\nseeds = 16\n",
        encoding="utf-8",
    )
    table = tmp_path / "out" / "results.csv"
    command = [sys.executable, "-m", "simmer", "sweep", str(sweep), "-o", str(tmp_path / "out")]
    stopped = subprocess.Popen(
        [*command, "--workers", "2"],
        start_new_session=True,  # its own process group, as a terminal's Ctrl-C reaches
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
    )

    def three_rows() -> bool:
        assert stopped.poll() is None
        return table.exists() and len(table.read_text(encoding="utf-8").splitlines()) > 3

    wait_for(three_rows, "three rows of results", 60)
    os.killpg(stopped.pid, signal.SIGINT)
    _, err = stopped.communicate(timeout=60)
    assert stopped.returncode == 130, err
    assert b"--resume goes on" in err
    finished = len(read_table(table))
    assert 3 <= finished < 16
    resumed = run_sweep(load_sweep(sweep), tmp_path / "out", workers=2, resume=True)
    assert resumed.ran == 16 - finished
    rows = read_table(table)
    assert [row["seed"] for row in rows] == [str(seed) for seed in range(16)]
    assert not (tmp_path / "out" / "results.csv.tmp").exists()
