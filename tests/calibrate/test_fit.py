"""The calibration fit: the routine's run cut into stops, moves and holds; each hidden setting
of a simulated robot inside its interval; the fragment a configuration takes; the quantiles
its intervals use."""

from __future__ import annotations

import tomllib
from pathlib import Path

import pytest

from routine_support import record_routine
from simmer.calibrate.fit import calibrate, fitted_overrides, fragment, segment
from simmer.calibrate.groundtruth import hidden_settings, team_config
from simmer.calibrate.routine import HOLDS, LEGS, TURNS, plan, routine_program
from simmer.calibrate.stats import chi2_quantile, t_quantile
from simmer.config import load_config
from simmer.config.overrides import with_overrides
from simmer.errors import CalibrationError, RoutineError
from simmer.tap.folder import load_tap_run
from simmer.world.simulation import Simulation


def test_quantiles_are_within_a_percent_of_the_tables() -> None:
    assert t_quantile(0.975, 10) == pytest.approx(2.2281, rel=0.01)
    assert t_quantile(0.975, 5) == pytest.approx(2.5706, rel=0.01)
    assert chi2_quantile(0.975, 10) == pytest.approx(20.483, rel=0.01)
    assert chi2_quantile(0.025, 10) == pytest.approx(3.247, rel=0.01)
    assert chi2_quantile(0.025, 100) == pytest.approx(74.222, rel=0.01)


@pytest.fixture(scope="module")
def team() -> object:
    return team_config(load_config())


@pytest.mark.parametrize("number", [101, 102])
def test_the_hidden_settings_fall_inside_their_intervals(
    tmp_path: Path, team: object, number: int
) -> None:
    config = team_config(load_config())
    hidden = hidden_settings(number, config)
    robot = Simulation(with_overrides(config, hidden), seed=number)
    record_routine(robot, config, tmp_path / "run")
    run = load_tap_run(tmp_path / "run")
    parts = segment(run.exchanges, config)
    assert len(parts.holds) == HOLDS
    assert len(parts.moves) - 2 * (LEGS + TURNS) in {0, 1}  # 1: back to the start to turn
    assert len(parts.stops) == 1 + HOLDS + len(parts.moves)
    result = calibrate(run, config)
    covered = [key for key, value in hidden.items() if result.value(key).covers(value)]
    assert len(covered) >= len(hidden) - 1, {
        k: (v, result.value(k).low, result.value(k).high) for k, v in hidden.items()
    }
    for key in hidden:  # every interval says something: not the whole line
        estimate = result.value(key)
        assert estimate.high - estimate.low < 0.2
    # the fragment is TOML a configuration takes, each value with its interval beside it
    text = fragment(result, "runs/x")
    data = tomllib.loads(text)
    assert data["drives"]["w0"]["bias"]["y"] == pytest.approx(
        result.value("drives.w0.bias.y").value, rel=1e-4
    )
    assert "# 99%: [" in text
    fitted = with_overrides(config, fitted_overrides(result))
    assert fitted.device("u0").params.error == pytest.approx(  # type: ignore[attr-defined]
        result.value("sensors.u0.error").value
    )


def test_a_run_that_is_not_the_routine_is_one_plain_error(tmp_path: Path) -> None:
    config = team_config(load_config())
    robot = Simulation(config, seed=1)
    from simmer.tap.decode import Exchange
    from simmer.tap.folder import TapRecorder

    recorder = TapRecorder(tmp_path / "run", config, "x")
    recorder.record(Exchange("w0-6", 1, recorder.start, robot.command("w0-6"), None))
    recorder.close(
        "x", False, bytes_sent=0, bytes_received=0, stray=0, program=None, program_status=None
    )
    with pytest.raises(CalibrationError, match="0 stop"):
        calibrate(load_tap_run(tmp_path / "run"), config)


def test_the_routine_program_is_python_for_this_robot() -> None:
    config = team_config(load_config())
    text = routine_program(config, plan(config))
    compile(text, "calibration_routine.py", "exec")
    assert "READ = 'u0,u1,u2,u3,g0'" in text
    assert "framed=False, width=4" in text


def test_a_robot_facing_a_wall_cannot_run_the_routine() -> None:
    config = with_overrides(load_config(), {"robot_start_rotation": 90})
    with pytest.raises(RoutineError, match="ahead of the robot's start"):
        plan(config)
