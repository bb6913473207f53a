"""TOML mistakes in a configuration: each names its line (both lines for a key or table set twice)
in plain words, and every toggle of the lab example is one edit."""

from __future__ import annotations

from pathlib import Path

import pytest
from typer.testing import CliRunner

from simmer.cli import app
from simmer.config import config_from_toml
from simmer.errors import ConfigError, ConfigIssue

from helpers import COMMENTED_SETTING, EXAMPLES, REPO, uncomment

LAB1 = EXAMPLES / "lab1_rover.toml"


def toml_problem(text: str) -> ConfigIssue:
    """The one issue a TOML text that does not load has."""
    with pytest.raises(ConfigError) as caught:
        config_from_toml(text, "robot.toml", REPO)
    (issue,) = caught.value.issues
    return issue


def test_each_toggle_of_the_lab_example_is_one_edit() -> None:
    """Uncommenting any commented-out setting (or all of them), or changing a sensor's
    ``error = 0`` as its comment says, gives a configuration that loads."""
    text = LAB1.read_text(encoding="utf-8")
    toggles = COMMENTED_SETTING.findall(text)
    assert any(t.startswith("bias") for t in toggles)
    assert any(t.startswith("error") for t in toggles)
    for toggle in toggles:
        config_from_toml(uncomment(text, toggle), str(LAB1), LAB1.parent)
    noisy = text
    for toggle in toggles:
        noisy = uncomment(noisy, toggle)
    noisy = noisy.replace("error = 0 ", "error = 0.02 ")
    config = config_from_toml(noisy, str(LAB1), LAB1.parent)
    errors = {spec.id: spec.params.error for spec in config.devices if spec.group == "sensors"}
    assert errors == dict.fromkeys(["u0", "u1", "u2", "u3"], 0.02)
    assert config.device("w0").params.bias.rotation == 0.2


def test_a_key_set_twice_names_both_lines() -> None:
    """What uncommenting ``# error = 0.02`` under ``error = 0`` did to the old example."""
    text = '[sensors.u0]\ntype = "ultrasonic"\nerror = 0\nerror = 0.02\n'
    issue = toml_problem(text)
    assert issue.line == 4
    assert issue.key == "sensors.u0.error"
    assert "set twice, on lines 3 and 4: keep one" in issue.message
    assert "quotes" not in issue.message  # it pointed the wrong way
    # the same at the very end of a file with no line ending (tomllib: "at end of document")
    assert toml_problem(text.rstrip("\n")).line == 4


def test_a_table_written_twice_names_both_lines() -> None:
    issue = toml_problem("[motors.m0]\nrotation = 0\n\n[motors.m1]\n\n[motors.m0]\n")
    assert issue.line == 6
    assert "the table [motors.m0] is written twice, on lines 1 and 6" in issue.message


def test_a_key_set_twice_around_multiline_values_and_strings() -> None:
    """The scan that finds the first line follows multi-line arrays and strings."""
    text = 'walls = [\n  [1, 1],\n]\nnote = """\nwalls = 3\n"""\nwalls = [[1]]\n'
    issue = toml_problem(text)
    assert (issue.key, issue.line) == ("walls", 7)
    assert "lines 1 and 7" in issue.message


@pytest.mark.parametrize(
    ("text", "line"),
    [
        ("frame_rate = 60\nwalls = [[1, 1],\n  [1 1]]\n", 3),
        ("robot_width = six\n", 1),
        ('frame_rate = 60\nhost = "127.0.0.1\n', 2),
        ("frame_rate = 60\nwalls = [[1, 1],\n", 2),  # tomllib: "at end of document"
        ("x = 1\n[x]\n", 2),
        ("a = {x = 1, x = 2}\n", 1),
    ],
)
def test_every_toml_problem_has_its_line_and_plain_words(text: str, line: int) -> None:
    issue = toml_problem(text)
    assert issue.line == line
    assert "(at " not in issue.message
    assert "end of document" not in issue.message


def test_simmer_check_shows_both_lines(tmp_path: Path) -> None:
    text = LAB1.read_text(encoding="utf-8").replace(
        "error = 0                       # Part 2, step 7: change to 0.02\n",
        "error = 0\nerror = 0.02\n",
        1,
    )
    path = tmp_path / "lab1.toml"
    path.write_text(text, encoding="utf-8")
    second = text.splitlines().index("error = 0.02") + 1
    result = CliRunner().invoke(app, ["check", str(path)])
    assert result.exit_code == 1
    assert f"{path}:{second}: sensors.u0.error: is set twice, on lines {second - 1} and " in (
        result.output
    )
