"""Broken configurations: each is refused with a message naming the offending key."""

from __future__ import annotations

import re
import subprocess
import sys
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest
import tomlkit
from typer.testing import CliRunner

from simmer.cli import app
from simmer.errors import ConfigError

from helpers import default_data, make_config

Data = dict[str, Any]


def set_key(*path: str | int, value: Any) -> Callable[[Data], None]:
    def mutate(data: Data) -> None:
        target: Any = data
        for part in path[:-1]:
            target = target[part]
        target[path[-1]] = value

    return mutate


def delete_key(*path: str) -> Callable[[Data], None]:
    def mutate(data: Data) -> None:
        target: Any = data
        for part in path[:-1]:
            target = target[part]
        del target[path[-1]]

    return mutate


def add_device(group: str, device_id: str, **settings: Any) -> Callable[[Data], None]:
    return set_key(group, device_id, value=settings)


BROKEN: list[tuple[str, Callable[[Data], None], str, str]] = [
    ("unknown top-level key", set_key("frame_rat", value=30), "frame_rat", "'frame_rate'"),
    ("unknown device key", set_key("sensors", "u0", "beamwith", value=10), "sensors.u0.beamwith",
     "'beamwidth'"),
    ("unknown nested key", set_key("drives", "w0", "bias", value={"rotaton": 0.2}),
     "drives.w0.bias.rotaton", "'rotation'"),
    ("wrong type", set_key("frame_rate", value="fast"), "frame_rate", "number"),
    ("negative frame rate", set_key("frame_rate", value=-60), "frame_rate", "greater than 0"),
    ("bad colour", set_key("wall_color", value=[255, 0, 300]), "wall_color", "255"),
    ("colour too short", set_key("robot_color", value=[255, 0]), "robot_color", ""),
    ("port out of range", set_key("port_rx", value=70000), "port_rx", "65535"),
    ("same ports", set_key("port_tx", value=61200), "port_tx", "port_rx"),
    ("reply width", set_key("reply_bytes", value=2), "reply_bytes", "4"),
    ("unknown encoding", set_key("str_encoding", value="utf-9"), "str_encoding", "utf-8"),
    ("empty walls", set_key("walls", value=[]), "walls", "empty"),
    ("ragged walls", set_key("walls", value=[[1, 1, 1], [1, 1]]), "walls[1]", "same number"),
    ("all-solid walls", set_key("walls", value=[[0, 0], [0, 0]]), "walls", "no open cell"),
    ("robot in a wall", set_key("robot_start_position", value=[18, 30]), "robot_start_position",
     "overlaps"),
    ("robot outside the maze", set_key("robot_start_position", value=[-10, 42]),
     "robot_start_position", "open cell"),
    ("block in a wall", set_key("block_position", value=[54, 6]), "block_position", "overlaps"),
    ("block on the robot", set_key("block_position", value=[6, 43]), "block_position", "robot"),
    ("duplicate device id", add_device("sensors", "m0", type="gyroscope"), "sensors.m0",
     "already used"),
    ("drive names unknown motor", set_key("drives", "w0", "motors", value=["m0", "m2"]),
     "drives.w0.motors[1]", "no motor 'm2'"),
    ("velocity and ang_velocity", set_key("drives", "w0", "ang_velocity", value=90),
     "drives.w0.ang_velocity", "never both"),
    ("drive that never moves", set_key("drives", "w0", "velocity", value=[0, 0]),
     "drives.w0.velocity", "non-zero"),
    ("motor_direction length", set_key("drives", "r0", "motor_direction", value=[1]),
     "drives.r0.motor_direction", "one direction"),
    ("motor_direction value", set_key("drives", "r0", "motor_direction", value=[1, 2]),
     "drives.r0.motor_direction[1]", "1 or -1"),
    ("sensor without type", delete_key("sensors", "u0", "type"), "sensors.u0.type",
     "ultrasonic"),
    ("unknown sensor kind", set_key("sensors", "u0", "type", value="ultrasound"),
     "sensors.u0.type", "'ultrasonic'"),
    ("kind in wrong table", set_key("sensors", "u0", "type", value="motor"), "sensors.u0.type",
     "[motors.u0]"),
    ("id too long", add_device("sensors", "us0", type="ultrasonic"), "sensors.us0",
     "two ASCII"),
    ("reserved id", add_device("sensors", "xx", type="compass"), "sensors.xx", "emergency stop"),
    ("id key inside table", set_key("sensors", "u0", "id", value="u0"), "sensors.u0.id",
     "name of its table"),
    ("max below min range", set_key("sensors", "u0", "min_range", value=500),
     "sensors.u0.max_range", "min_range"),
    ("beamwidth too wide", set_key("sensors", "u0", "beamwidth", value=200),
     "sensors.u0.beamwidth", "180"),
    ("simulate_list names a motor", set_key("simulate_list", value=["m0"]), "simulate_list[0]",
     "is a motor"),
    ("simulate_list typo", set_key("simulate_list", value=["uO"]), "simulate_list[0]",
     "no sensor 'uO'"),
    ("outline too short", set_key("robot_outline", value=[[0, 0], [1, 1]]), "robot_outline",
     "3"),
    ("missing plugin file", set_key("plugins", value=["nowhere.py"]), "plugins[0]",
     "no file"),
    ("devices not a table", set_key("motors", value=[1, 2]), "motors", "table"),
    ("negative bias strength", set_key("bias_strength", value=[-1, 0]), "bias_strength",
     "0 or more"),
]  # fmt: skip


@pytest.mark.parametrize(
    ("mutate", "key", "fragment"),
    [pytest.param(m, k, f, id=name) for name, m, k, f in BROKEN],
)
def test_broken_configuration_names_the_key(
    mutate: Callable[[Data], None], key: str, fragment: str
) -> None:
    data = default_data()
    mutate(data)
    with pytest.raises(ConfigError) as caught:
        make_config(data)
    keys = [issue.key for issue in caught.value.issues]
    assert key in keys, caught.value.render()
    message = next(issue.message for issue in caught.value.issues if issue.key == key)
    assert fragment in message


def test_every_issue_is_reported_at_once() -> None:
    data = default_data()
    data["frame_rat"] = 30
    data["sensors"]["u0"]["beamwith"] = 10
    data["drives"]["w0"]["motors"] = ["m0", "m9"]
    with pytest.raises(ConfigError) as caught:
        make_config(data)
    assert len(caught.value.issues) == 3


def write_broken(tmp_path: Path, name: str, mutate: Callable[[Data], None]) -> Path:
    data = default_data()
    mutate(data)
    path = tmp_path / f"{name.replace(' ', '_')}.toml"
    path.write_text(tomlkit.dumps(data), encoding="utf-8")
    return path


@pytest.mark.slow
def test_simmer_check_reports_each_broken_file_with_exit_1(tmp_path: Path) -> None:
    runner = CliRunner()
    for name, mutate, key, _ in BROKEN:
        path = write_broken(tmp_path, name, mutate)
        result = runner.invoke(app, ["check", str(path)])
        assert result.exit_code == 1, name
        assert result.exception is None or isinstance(result.exception, SystemExit), name
        shown = result.output.replace("\n  ", " ")
        assert re.search(rf"{re.escape(str(path))}(:\d+)?: {re.escape(key)}", shown), (name, shown)


@pytest.mark.slow
def test_simmer_check_as_a_process_prints_no_traceback(tmp_path: Path) -> None:
    path = write_broken(tmp_path, "typo", set_key("frame_rat", value=30))
    done = subprocess.run(
        [sys.executable, "-m", "simmer", "check", str(path)],
        capture_output=True,
        text=True,
        check=False,
    )
    assert done.returncode == 1
    assert "Traceback" not in done.stderr + done.stdout
    assert "frame_rat: unknown key (did you mean 'frame_rate'?)" in done.stderr


def test_invalid_toml_reports_the_line(tmp_path: Path) -> None:
    path = tmp_path / "bad.toml"
    path.write_text("frame_rate = 60\nwalls = [[1, 1],\n  [1 1]]\n", encoding="utf-8")
    with pytest.raises(ConfigError) as caught:
        make_config_file(path)
    assert caught.value.issues[0].line == 3
    assert f"{path}:3:" in caught.value.render()


def make_config_file(path: Path) -> None:
    from simmer.config import load_config

    load_config(path)


def test_simmer_check_ok_prints_summary() -> None:
    result = CliRunner().invoke(app, ["check", "examples/lab1_rover.toml"])
    assert result.exit_code == 0
    assert result.output.startswith("OK examples/lab1_rover.toml")
    assert "4 sensors" in result.output
