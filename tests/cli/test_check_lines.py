"""``simmer check`` reports every problem, each with its line, and the command line's
settings pass the same checks as the file's."""

from __future__ import annotations

import socket
from pathlib import Path

import pytest
from typer.testing import CliRunner

from simmer.cli import app
from simmer.config import load_config, with_overrides
from simmer.errors import ConfigError

from helpers import EXAMPLES

LAB1 = (EXAMPLES / "lab1_rover.toml").read_text(encoding="utf-8")


def line_of(text: str, start: str) -> int:
    """The 1-based number of the first line of ``text`` starting with ``start``."""
    return next(i for i, line in enumerate(text.splitlines(), 1) if line.startswith(start))


def edited(tmp_path: Path, *changes: tuple[str, str]) -> tuple[Path, str]:
    """The lab rover with each (old, new) text replaced once, written to a file."""
    text = LAB1
    for old, new in changes:
        assert old in text, old
        text = text.replace(old, new, 1)
    path = tmp_path / "rover.toml"
    path.write_text(text, encoding="utf-8")
    return path, text


def check(path: Path) -> tuple[int, list[str]]:
    result = CliRunner().invoke(app, ["check", str(path)])
    return result.exit_code, result.output.splitlines()


def test_three_problems_in_one_table_are_three_lines_each_with_its_line(tmp_path: Path) -> None:
    path, text = edited(
        tmp_path,
        ('motors = ["m0", "m1"]\nmotor_direction = [1, 1]\n',
         'motors = ["m0", "m2"]\nmotor_direction = [1, 1]\nmotor_directon = [1, 1]\nvelocty = 3\n'),
    )  # fmt: skip
    status, lines = check(path)
    motors = line_of(text, 'motors = ["m0", "m2"]')
    assert status == 1
    assert lines[0] == f"3 problems in {path}:"
    assert lines[1:] == [
        f"  {path}:{motors}: drives.w0.motors[1]: no motor 'm2'; the motors are: m0, m1",
        f"  {path}:{line_of(text, 'motor_directon')}: drives.w0.motor_directon: unknown key "
        "(did you mean 'motor_direction'?); check its spelling or delete it",
        f"  {path}:{line_of(text, 'velocty')}: drives.w0.velocty: unknown key (did you mean "
        "'velocity'?); check its spelling or delete it",
    ]


def test_an_unknown_key_does_not_hide_a_mistake_between_settings(tmp_path: Path) -> None:
    path, _ = edited(
        tmp_path,
        ("motor_direction = [1, 1]\n", "motor_direction = [1]\nvelocty = 3\n"),
        ("[sensors.u0]\n", "[sensors.u0]\nbeamwith = 3\nmin_range = 500\n"),  # past max_range
    )  # fmt: skip
    status, lines = check(path)
    assert status == 1
    shown = [line.split(": ", 2)[1:] for line in lines[1:]]
    assert [key for key, _ in shown] == [
        "drives.w0.motor_direction",
        "drives.w0.velocty",
        "sensors.u0.max_range",  # not written: the line of its table
        "sensors.u0.beamwith",
    ]
    assert shown[0][1].startswith("has 1 entries but motors has 2")
    assert shown[2][1] == "must be greater than min_range (500), got 433"


def test_a_value_mistake_has_its_line(tmp_path: Path) -> None:
    path, text = edited(
        tmp_path,
        ("rotation = -90\nheight = 1\nerror = 0", "rotation = -90\nheight = 1\nerror = -2"),
    )
    status, lines = check(path)
    wrong = next(i for i, line in enumerate(text.splitlines(), 1) if line.startswith("error = -2"))
    assert status == 1
    assert lines[1] == f"  {path}:{wrong}: sensors.u1.error: must be 0 or more, not -2"


def test_a_missing_key_points_at_its_table(tmp_path: Path) -> None:
    path, text = edited(tmp_path, ('[sensors.u2]\ntype = "ultrasonic"\n', "[sensors.u2]\n"))
    status, lines = check(path)
    assert status == 1
    assert lines[1].startswith(
        f"  {path}:{line_of(text, '[sensors.u2]')}: sensors.u2.type: missing"
    )


def test_problems_in_several_tables_come_in_the_files_order(tmp_path: Path) -> None:
    path, text = edited(
        tmp_path,
        ("[sensors.u0]\n", "[sensors.u0]\nbeamwith = 3\n"),
        ('motors = ["m0", "m1"]', 'motors = ["m0", "m9"]'),
        ("simulate_list = [", "frame_rate = -1\nsimulate_list = ["),
    )  # fmt: skip
    status, lines = check(path)
    assert status == 1
    numbers = [int(line.split(":")[1]) for line in lines[1:]]
    assert len(numbers) == 3
    assert numbers == sorted(numbers)
    assert numbers == [line_of(text, "frame_rate"), line_of(text, 'motors = ["m0", "m9"]'),
                       line_of(text, "beamwith")]  # fmt: skip


def test_settings_from_the_command_line_pass_the_files_checks(tmp_path: Path) -> None:
    with socket.create_server(("127.0.0.1", 0)) as sock:
        port = sock.getsockname()[1]  # nothing may bind it: the check comes first
        result = CliRunner().invoke(
            app,
            ["run", str(EXAMPLES / "lab1_rover.toml"), "--headless", "--seconds", "0.1",
             "--port-rx", str(port), "--port-tx", str(port), "--port", "0"],
        )  # fmt: skip
    assert result.exit_code == 1
    assert (
        f"with --port-rx {port} --port-tx {port}: port_tx: must differ from port_rx ({port})"
        in (result.output)
    )
    assert "Address already in use" not in result.output


def test_a_bad_override_from_python_is_a_config_error() -> None:
    config = load_config(EXAMPLES / "lab1_rover.toml")
    with pytest.raises(ConfigError, match=r"port_rx: must be 65535 or less, not 70000"):
        with_overrides(config, {"port_rx": 70000}, "the command line")
    with pytest.raises(ConfigError, match=r"port_tx: must differ from port_rx \(61201\)"):
        with_overrides(config, {"port_rx": 61201})
    assert with_overrides(config, {"port_rx": 50000}).settings.port_rx == 50000
