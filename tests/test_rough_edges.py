"""The rough edges a new user hit (issue 9): each reproduction, and what a student sees now."""

from __future__ import annotations

import importlib.metadata
import logging
import math
import os
import re
import shutil
import socket
import stat
import subprocess
from pathlib import Path

import pytest
from typer.testing import CliRunner

from link_support import serving
from simmer.cli import app
from simmer.config import config_from_toml, load_config
from simmer.config.convert import convert_simmer_py
from simmer.console import HELP, run_console
from simmer.errors import ConfigError, ConfigIssue
from simmer.options import RunOptions
from simmer.protocol import Decoded, parse_command, printable
from simmer.runner import Runner
from simmer.serve import serve
from simmer.transport.bus import Request
from simmer.ui import RecordingRenderer
from simmer.ui.hud import paint_hud
from simmer.view.commands import CommandLog, RepeatedCommand
from simmer.view.snapshot import Snapshot
from simmer.world import Simulation
from simmer.world.events import CommandEvent, Event

from helpers import EXAMPLES, REPO, SIMMER_PY

LAB1 = EXAMPLES / "lab1_rover.toml"
COMMENTED_SETTING = re.compile(r"^# ([A-Za-z_]+ = .*)$", re.MULTILINE)
"""A setting commented out: ``# bias = {...}`` (prose comments have no ``key = ``)."""


def toml_problem(text: str) -> ConfigIssue:
    """The one issue a TOML text that does not load has."""
    with pytest.raises(ConfigError) as caught:
        config_from_toml(text, "robot.toml", REPO)
    (issue,) = caught.value.issues
    return issue


def uncomment(text: str, line: str) -> str:
    """``text`` with the commented-out ``line`` (``bias = ...``) made a setting."""
    return text.replace(f"# {line}", line, 1)


# ----------------------------------------------------------------------------- the example


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


# ----------------------------------------------------------------------------- convert


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


# ----------------------------------------------------------------------------- window and HUD


def test_repeated_polls_take_one_hud_line() -> None:
    """``wait_idle()`` polls ``w0-0`` until the drive is done: one line with a count."""
    sim = Simulation.from_config()
    log = CommandLog()
    sim.add_observer(log)
    sim.command("u0")
    sim.command("w0-12")
    polls = 0
    while math.isnan(sim.command("w0-0")[0]):
        polls += 1
        sim.step(3)
    assert polls > 5
    entries = list(log.entries)
    assert [e.message for e in entries] == ["u0", "w0-12", "w0-0", "w0-0"]
    assert isinstance(entries[2], RepeatedCommand)
    assert entries[2].count == polls
    rec = RecordingRenderer()
    paint_hud(rec, Snapshot.of(sim, commands=entries))
    texts = [str(args[0]) for args in rec.of("text")]
    assert any(t.endswith(f"w0-0 -> NaN  x{polls}") for t in texts)
    assert any(" u0 -> " in t for t in texts)  # the student's own command is still shown


def test_the_window_says_one_thing_when_no_screen_is_found(
    caplog: pytest.LogCaptureFixture, monkeypatch: pytest.MonkeyPatch
) -> None:
    said: list[str] = []
    with caplog.at_level(logging.WARNING, logger="simmer.ui"):
        serve(
            Simulation.from_config(),
            RunOptions.free_ports(window=True, speed=None, seconds=0.1),
            echo=said.append,
        )
    assert "no screen found" in caplog.text
    assert not any("window open" in line for line in said)
    # with a screen, the window says it is open
    from simmer.ui import window

    monkeypatch.setattr(window.pygame.display, "get_driver", lambda: "x11")
    said.clear()
    serve(
        Simulation.from_config(),
        RunOptions.free_ports(window=True, speed=None, seconds=0.1),
        echo=said.append,
    )
    assert "window open (press h for help)" in said


# ----------------------------------------------------------------------------- console and CLI


def test_console_answers_help_itself() -> None:
    lines = iter(["help", "?", "u0", "quit"])
    shown: list[str] = []
    sim = Simulation.from_config()
    seen: list[Event] = []
    sim.add_observer(seen.append)
    with serving(sim) as (_, link):
        from simmer.client import connect

        with connect(port=link.stream.port) as client:
            run_console(client, read=lambda _: next(lines), echo=shown.append, history=False)
    assert shown[:3] == [HELP, HELP, HELP]
    commands = [e.message for e in seen if isinstance(e, CommandEvent)]
    assert commands == ["u0"]  # help never reached the simulator


def test_version() -> None:
    result = CliRunner().invoke(app, ["--version"])
    assert result.exit_code == 0, result.output
    assert result.output.strip() == f"simmer {importlib.metadata.version('simmer')}"


def test_keys_prints_no_note_for_developers() -> None:
    result = CliRunner().invoke(app, ["keys"])
    assert result.exit_code == 0
    assert "do not edit" not in result.output
    assert "rand_error" in result.output


def free_port() -> int:
    """A TCP port nothing listens on right now."""
    with socket.create_server(("127.0.0.1", 0)) as sock:
        port: int = sock.getsockname()[1]
    return port


def test_the_start_up_summary_shows_the_ports_in_use() -> None:
    rx, tx, stream = free_port(), free_port(), free_port()
    result = CliRunner().invoke(
        app,
        ["run", "--headless", "--speed", "max", "--seconds", "0.05",
         "--port-rx", str(rx), "--port-tx", str(tx), "--port", str(stream)],
    )  # fmt: skip
    assert result.exit_code == 0, result.output
    assert f"127.0.0.1 rx {rx}, tx {tx}" in result.output
    assert f"port {stream}" in result.output
    assert "61200" not in result.output


def test_an_ipv6_host_is_not_blamed_on_another_simmer() -> None:
    result = CliRunner().invoke(
        app,
        ["run", "--headless", "--seconds", "0.05", "--host", "::", "--port-rx", "0",
         "--port-tx", "0", "--port", "0"],
    )  # fmt: skip
    assert result.exit_code == 1
    assert "another simmer" not in result.output
    assert "cannot serve on '::'" in result.output
    assert "IPv4" in result.output


def test_a_port_in_use_may_be_another_simmer() -> None:
    with socket.create_server(("127.0.0.1", 0)) as taken:
        port = taken.getsockname()[1]
        result = CliRunner().invoke(
            app,
            ["run", "--headless", "--seconds", "0.05", "--port-rx", str(port),
             "--port-tx", "0", "--port", "0"],
        )  # fmt: skip
    assert result.exit_code == 1
    assert "Another simmer run (or another program) is using this port" in result.output


# ----------------------------------------------------------------------------- commands and logs


@pytest.mark.parametrize("text", ["u0-٥", "w0-６", "w0-١٢", "w0-\u20075", "w0-5\u0665"])
@pytest.mark.parametrize("lenient", [False, True])
def test_digits_outside_ascii_are_not_numbers(text: str, lenient: bool) -> None:
    command = parse_command(text, lenient=lenient)
    assert command.error is not None
    assert "ASCII" in command.error


def test_a_config_py_run_answers_nan_to_digits_outside_ascii() -> None:
    sim = Simulation(load_config(SIMMER_PY / "lab_rover_quiet.py"))
    assert math.isnan(sim.command("w0-６")[0])
    assert sim.command("w0-6") == [math.inf]


CONTROL = "\x1b[2J\x1b[31m\u202eevil\x07"
"""Clear the screen, turn red, reverse the line, ring the bell."""


@pytest.mark.parametrize("config", [None, SIMMER_PY / "lab_rover_quiet.py"])
def test_client_text_is_escaped_in_the_log(
    config: Path | None, caplog: pytest.LogCaptureFixture
) -> None:
    sim = Simulation(load_config(config))
    messages = [CONTROL, f"w0{CONTROL}", f"{CONTROL[:2]}-1", f"{CONTROL[:2]}x1", f"u0-{CONTROL}"]
    with caplog.at_level(logging.DEBUG):
        for message in messages:
            sim.command(message)
        Runner(sim).handle(Request(Decoded(None, 1, f"not text: {CONTROL}"), "client"))
    logged = [record.getMessage() for record in caplog.records]
    assert len(logged) >= len(messages)
    for line in logged:
        assert line.isprintable(), line
    assert any("\\x1b[2J" in line for line in logged)


def test_printable_escapes_only_what_is_not_printable() -> None:
    assert printable("w0-6 ٥ é") == "w0-6 ٥ é"
    assert printable("a\x1bb\u202ec\n") == "a\\x1bb\\u202ec\\n"
    assert printable(repr("\x1b")) == repr("\x1b")  # already escaped: unchanged


# ----------------------------------------------------------------------------- scripts and docs


def fake_repo(tmp_path: Path, script: str) -> tuple[Path, Path]:
    """A copy of ``scripts/<script>`` in a repository whose python3, pip and tools only log
    what they are asked to do; returns the script and the log."""
    repo = tmp_path / "repo"
    (repo / "scripts").mkdir(parents=True)
    shutil.copy(REPO / "scripts" / script, repo / "scripts" / script)
    (repo / "pyproject.toml").write_text("[project]\nname = 'simmer'\n", encoding="utf-8")
    calls = tmp_path / "calls.log"
    fake = f'#!/usr/bin/env bash\necho "$(basename "$0") $*" >> {calls}\n'
    venv_bin = repo / ".venv" / "bin"
    path_bin = tmp_path / "bin"
    venv_bin.mkdir(parents=True)
    path_bin.mkdir()
    for directory, names in ((venv_bin, ("python", "simmer", "ruff", "mypy", "pytest")),
                             (path_bin, ("python3",))):  # fmt: skip
        for name in names:
            tool = directory / name
            tool.write_text(fake, encoding="utf-8")
            tool.chmod(tool.stat().st_mode | stat.S_IEXEC)
    return repo / "scripts" / script, calls


@pytest.mark.skipif(shutil.which("bash") is None, reason="the scripts are bash")
@pytest.mark.parametrize(
    ("script", "expected"),
    [
        ("run.sh", ["python3 scripts/setup.py", "simmer run --speed 2"]),
        ("test.sh", ["python3 scripts/setup.py --test", "ruff check .", "ruff format --check .",
                     "mypy", "pytest --speed 2"]),
    ],
)  # fmt: skip
def test_scripts_set_up_then_work(tmp_path: Path, script: str, expected: list[str]) -> None:
    """The set-up itself (only when needed) is scripts/setup.py's: test_fresh_clone.py."""
    path, calls = fake_repo(tmp_path, script)
    env = {**os.environ, "PATH": f"{tmp_path / 'bin'}{os.pathsep}{os.environ['PATH']}"}
    subprocess.run(["bash", str(path), "--speed", "2"], env=env, check=True, capture_output=True)
    assert [line.strip() for line in calls.read_text(encoding="utf-8").splitlines()] == expected


def test_docs_say_that_configurations_run_code() -> None:
    for doc in ("README.md", "docs/migrating.md", "docs/devices.md"):
        text = " ".join((REPO / doc).read_text(encoding="utf-8").split())
        assert "configurations you trust" in text, doc
