"""``simmer convert``: SimMeR config.py -> native TOML, comments kept, round trip exact."""

from __future__ import annotations

import tomllib
from pathlib import Path

import pytest
from typer.testing import CliRunner

from simmer.cli import app
from simmer.config import config_from_toml, load_config
from simmer.config.convert import convert_simmer_py

from helpers import COMMENTED_SETTING, SIMMER_PY, SIMMER_PY_FILES, uncomment

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


def test_convert_carries_commented_out_settings() -> None:
    """The quiet lab rover, converted, becomes the noisy one by uncommenting lines."""
    text = convert_simmer_py(SIMMER_PY / "lab_rover_quiet.py")
    w0 = text.split("[drives.w0]")[1].split("\n\n")[0]
    assert "# bias = {x = 0, y = 0, rotation = 0.2}" in w0.splitlines()
    assert "# error = {x = 0.02, y = 0.05, rotation = 1}" in w0.splitlines()
    assert "# error = 0.02" in text.split("[sensors.u0]")[1].split("\n\n")[0].splitlines()
    top_level = text.split("\n[")[0]
    assert '# simulate_list = ["u0", "u1", "u2", "u3"]' in top_level.splitlines()
    noisy = text
    for toggle in COMMENTED_SETTING.findall(text):
        noisy = uncomment(noisy, toggle)
    converted = config_from_toml(noisy, "noisy.toml", SIMMER_PY)
    original = load_config(SIMMER_PY / "lab_rover_noisy.py")
    assert converted.devices == original.devices
    assert converted.settings == original.settings


def test_convert_leaves_out_comments_no_longer_true(tmp_path: Path) -> None:
    """The original's "placeholder, not implemented": SimMeR 2 draws drive biases."""
    text = (SIMMER_PY / "lab_rover_quiet.py").read_text(encoding="utf-8")
    text = text.replace(
        "# Randomized drive bias",
        "# Use a randomized, normally distributed set of bias values for drives "
        "(placeholder, not implemented)",
    ).replace(
        "# How intense the random drive bias is",
        "# How intense the random drive bias is, if enabled (placeholder, not implemented)",
    )
    config = tmp_path / "config.py"
    config.write_text(text, encoding="utf-8")
    converted = convert_simmer_py(config)
    assert "placeholder" not in converted
    assert (
        "rand_bias = false # Use a randomized, normally distributed set of bias values for drives"
        in converted.splitlines()
    )


def test_convert_says_which_line_a_commented_setting_replaces(tmp_path: Path) -> None:
    text = (SIMMER_PY / "lab_rover_quiet.py").read_text(encoding="utf-8")
    text = text.replace("    #'error': 0.02,", "    'error': 0.0,\n    #'error': 0.02,  # noisy")
    config = tmp_path / "config.py"
    config.write_text(text, encoding="utf-8")
    u0 = convert_simmer_py(config).split("[sensors.u0]")[1].split("\n\n")[0].splitlines()
    assert "error = 0.0" in u0
    assert "# error = 0.02  # noisy; uncomment only after deleting the other `error` line" in u0
