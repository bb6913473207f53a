"""``simmer calibrate`` and ``simmer compare`` on the command line: the routine written, a
run fitted into fitted.toml, its report and plots, the comparison with the fitted fragment;
a folder that is not a tap's is one plain line."""

from __future__ import annotations

import tomllib
from pathlib import Path

import pytest
from typer.testing import CliRunner

from routine_support import record_routine, record_short_run
from simmer.calibrate.groundtruth import hidden_settings, team_config
from simmer.cli import app
from simmer.config import load_config
from simmer.config.overrides import with_overrides
from simmer.world.simulation import Simulation

from helpers import REPO


@pytest.mark.slow
@pytest.mark.timeout(600)
def test_calibrate_then_compare_with_the_fitted_fragment(tmp_path: Path) -> None:
    rover = REPO / "examples" / "lab1_rover.toml"
    config = tmp_path / "robot.toml"  # the lab's rover with a gyroscope
    config.write_text(rover.read_text() + "\n[sensors.g0]\ntype = 'gyroscope'\nerror = 0.02\n")
    team = team_config(load_config(rover))
    robot = Simulation(with_overrides(team, hidden_settings(3, team)), seed=3)
    record_routine(robot, team, tmp_path / "run")
    result = CliRunner().invoke(
        app, ["calibrate", str(tmp_path / "run"), "--out", str(tmp_path / "fit"), "--seeds", "10"]
    )
    assert result.exit_code == 0, result.output
    fitted = tmp_path / "fit" / "fitted.toml"
    data = tomllib.loads(fitted.read_text())
    assert set(data["drives"]) == {"w0", "r0"}
    assert set(data["sensors"]) == {"u0", "u1", "u2", "u3", "g0"}
    for name in ("readings.png", "drives.png"):
        assert (tmp_path / "fit" / name).read_bytes()[:4] == b"\x89PNG"
    report = (tmp_path / "fit" / "calibration.md").read_text()
    assert "| `drives.w0.bias.y` |" in report
    assert "![The readings against the fitted simulator's band](readings.png)" in report
    compared = CliRunner().invoke(
        app,
        ["compare", str(tmp_path / "run"), "--config", str(config), "--fitted", str(fitted),
         "--seeds", "10"],
    )  # fmt: skip
    assert compared.exit_code == 0, compared.output
    assert "real readings" in compared.output
    assert (tmp_path / "run" / "compare.png").read_bytes()[:4] == b"\x89PNG"
    # the band carries the fit's intervals (kept beside the fragment) unless told not to
    intervals = tomllib.loads((tmp_path / "fit" / "fitted.intervals.toml").read_text())
    assert set(intervals) == set(fitted_keys(data))
    assert "each seed draws 9 fitted settings from the intervals in" in compared.output
    assert "each drawing 9 fitted settings from their intervals" in compared.output
    point = CliRunner().invoke(
        app,
        ["compare", str(tmp_path / "run"), "--config", str(config), "--fitted", str(fitted),
         "--seeds", "10", "--point-values"],
    )  # fmt: skip
    assert point.exit_code == 0, point.output
    assert "fitted settings" not in point.output


def fitted_keys(data: dict[str, object], prefix: str = "") -> list[str]:
    """A TOML document's dotted keys."""
    keys: list[str] = []
    for key, value in data.items():
        keys += fitted_keys(value, f"{prefix}{key}.") if isinstance(value, dict) else [prefix + key]
    return keys


def test_the_routine_is_written_for_the_configuration(tmp_path: Path) -> None:
    target = tmp_path / "routine.py"
    result = CliRunner().invoke(
        app,
        ["calibrate", "--config", str(REPO / "examples" / "lab1_rover.toml"), "--routine",
         str(target)],
    )  # fmt: skip
    assert result.exit_code == 0, result.output
    text = target.read_text()
    compile(text, str(target), "exec")
    assert "READ = 'u0,u1,u2,u3'" in text


@pytest.mark.parametrize("command", ["calibrate", "compare"])
def test_a_folder_that_is_not_a_taps_is_one_line(tmp_path: Path, command: str) -> None:
    (tmp_path / "run").mkdir()
    (tmp_path / "run" / "manifest.json").write_text('{"format": 1, "seed": 3}')
    args = [command, str(tmp_path / "run")]
    if command == "compare":
        args += ["--config", str(REPO / "examples" / "simmer_default.toml")]
    result = CliRunner().invoke(app, args)
    assert result.exit_code == 1
    lines = result.output.strip().splitlines()
    assert len(lines) == 1
    assert "not a tap's run folder" in lines[0]


@pytest.mark.slow  # draws compare.png twice: about 2 CPU s, the quick loop's bound
def test_compare_says_which_fitted_settings_it_draws(tmp_path: Path) -> None:
    team = team_config(load_config())
    record_short_run(Simulation(team, seed=2), team, tmp_path / "run")
    config = REPO / "examples" / "simmer_default.toml"  # it has a gyroscope g0
    fitted = tmp_path / "fitted.toml"
    fitted.write_text("[drives.w0]\nbias.y = 0.01\n\n[sensors.u0]\nerror = 0.02\n")
    side = tmp_path / "fitted.intervals.toml"
    side.write_text(
        '["drives.w0.bias.y"]\nvalue = 0.01\nlow = -0.01\nhigh = 0.03\nlevel = 0.99\n'
        '["sensors.u0.error"]\nvalue = 0.01\nlow = 0.008\nhigh = 0.012\nlevel = 0.99\n'
    )
    args = ["compare", str(tmp_path / "run"), "--config", str(config), "--fitted", str(fitted),
            "--seeds", "3"]  # fmt: skip
    result = CliRunner().invoke(app, args)
    assert result.exit_code == 0, result.output
    # u0's error was edited after the fit: compared at the file's value, and said so
    assert "sensors.u0.error: " in result.output
    assert "each seed draws 1 fitted settings from the intervals in" in result.output
    side.write_text('["drives.w0.bias.y"]\nvalue = 0.01\nlow = 0.02\nhigh = 0.03\nlevel = 0.99\n')
    broken = CliRunner().invoke(app, args)
    assert broken.exit_code == 1
    assert broken.output.strip().splitlines() == [
        f'{side}: ["drives.w0.bias.y"] needs low <= value <= high and 0 < level < 1; write it '
        "again with simmer calibrate"
    ]
    side.unlink()
    alone = CliRunner().invoke(app, args)
    assert alone.exit_code == 0, alone.output
    assert f"no intervals beside {fitted} (fitted.intervals.toml)" in alone.output
