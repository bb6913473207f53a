"""``simmer convert``: SimMeR config.py -> native TOML, comments kept, round trip exact."""

from __future__ import annotations

import tomllib
from pathlib import Path

import pytest
from typer.testing import CliRunner

from simmer.cli import app
from simmer.config import load_config
from simmer.config.convert import convert_simmer_py

from helpers import SIMMER_PY_FILES

DEFAULT, QUIET, NOISY, WITH_DEVICE, TOF_DEVICE = ALL = SIMMER_PY_FILES


def line_with(text: str, start: str) -> str:
    """The line of ``text`` that starts with ``start``."""
    return next(line for line in text.splitlines() if line.startswith(start))


@pytest.mark.parametrize("path", ALL, ids=lambda p: p.parent.name + "/" + p.name)
def test_round_trip_gives_an_identical_configuration(path: Path, tmp_path: Path) -> None:
    toml = tmp_path / "robot.toml"
    convert_simmer_py(path, toml)
    original, converted = load_config(path), load_config(toml)
    assert converted.settings == original.settings
    assert converted.devices == original.devices
    assert converted.source == str(toml)


@pytest.mark.parametrize("path", ALL, ids=lambda p: p.parent.name + "/" + p.name)
def test_converting_the_converted_data_is_stable(path: Path, tmp_path: Path) -> None:
    first = convert_simmer_py(path, tmp_path / "a.toml")
    assert convert_simmer_py(path, tmp_path / "b.toml") == first
    assert tomllib.loads(first)  # valid TOML


def test_comments_next_to_settings_are_carried_over() -> None:
    text = convert_simmer_py(DEFAULT)
    assert line_with(text, "robot_width = 6") == "robot_width = 6 # Robot width in inches"
    assert line_with(text, "robot_outline =").endswith("# Robot outline, relative to its centre")
    assert "] # Matrix defining the maze walls" in text  # after the multi-line walls array
    assert line_with(text, "velocity = [-6, 0]").endswith("# sideways")
    assert line_with(text, "height = 4").endswith("# above the block: cannot see it")
    assert 'frame_start = "["' in text  # SimMeR v1.2's frames are a setting now
    assert "maze_dim_x" not in text


@pytest.mark.parametrize(
    ("path", "version", "chosen"),
    [
        (DEFAULT, "v1.2", ['protocol = "framed"']),
        (QUIET, "v1.0", ['protocol = "packed"', "reply_bytes = 8"]),
    ],
)
def test_the_detected_version_is_written_out(path: Path, version: str, chosen: list[str]) -> None:
    text = convert_simmer_py(path)
    lines = text.splitlines()
    said = next(i for i, line in enumerate(lines) if f"looks like a SimMeR {version}" in line)
    assert lines[said + 2 : said + 3 + len(chosen)] == [*chosen, "lenient_commands = true"]


def test_device_entry_comment_goes_on_its_table_header() -> None:
    text = convert_simmer_py(WITH_DEVICE)
    assert "[sensors.b0] # the user's own device" in text
    assert line_with(text, "position = [0, -2]").endswith("# at the back of the rover")
    assert "plugins" not in text  # simmer_device is a built-in kind


def test_commented_out_lines_are_not_settings() -> None:
    data = tomllib.loads(convert_simmer_py(QUIET))
    assert "bias" not in data["drives"]["w0"]
    assert "error" not in data["drives"]["r0"]
    assert "error" not in data["sensors"]["u0"]
    assert "simulate_list" not in data


def test_user_device_module_path_is_relative_to_the_output(tmp_path: Path) -> None:
    out = tmp_path / "elsewhere" / "robot.toml"
    out.parent.mkdir()
    convert_simmer_py(WITH_DEVICE, out)
    module = tomllib.loads(out.read_text(encoding="utf-8"))["sensors"]["b0"]["module"]
    assert not Path(module).is_absolute()
    assert (out.parent / module).resolve() == WITH_DEVICE.parent / "devices" / "beacon.py"
    assert load_config(out).devices == load_config(WITH_DEVICE).devices


def test_cli_convert_writes_the_file(tmp_path: Path) -> None:
    out = tmp_path / "robot.toml"
    result = CliRunner().invoke(app, ["convert", str(NOISY), "-o", str(out)])
    assert result.exit_code == 0, result.output
    assert "wrote" in result.output
    assert load_config(out).devices == load_config(NOISY).devices
    check = CliRunner().invoke(app, ["check", str(out)])
    assert check.exit_code == 0, check.output


def test_cli_convert_prints_without_output() -> None:
    result = CliRunner().invoke(app, ["convert", str(QUIET)])
    assert result.exit_code == 0, result.output
    assert "[drives.w0]" in result.output


def test_cli_convert_refuses_a_broken_file(tmp_path: Path) -> None:
    broken = tmp_path / "config.py"
    broken.write_text("motors = {}\ndrives = {}\n", encoding="utf-8")
    out = tmp_path / "robot.toml"
    result = CliRunner().invoke(app, ["convert", str(broken), "-o", str(out)])
    assert result.exit_code == 1
    assert "Traceback" not in result.output
    assert "sensors" in result.output
    assert not out.exists()
