"""Help pages, the version and the key list, as a user reads them; help loads nothing heavy."""

from __future__ import annotations

import importlib.metadata
import subprocess
import sys

import pytest
from typer.testing import CliRunner

from simmer.cli import app


def test_version() -> None:
    result = CliRunner().invoke(app, ["--version"])
    assert result.exit_code == 0, result.output
    assert result.output.strip() == f"simmer {importlib.metadata.version('simmer')}"


def test_keys_prints_no_note_for_developers() -> None:
    result = CliRunner().invoke(app, ["keys"])
    assert result.exit_code == 0
    assert "do not edit" not in result.output
    assert "rand_error" in result.output


COMMANDS = [
    "new",
    "check",
    "keys",
    "run",
    "convert",
    "export-map",
    "table",
    "plot",
    "replay",
    "render",
    "sweep",
    "grade",
    "console",
    "tap",
    "calibrate",
    "compare",
    "maze",
]


@pytest.mark.parametrize("command", COMMANDS)
def test_each_help_page_is_as_written_with_an_example(command: str) -> None:
    result = CliRunner().invoke(app, [command, "--help"], terminal_width=100)
    assert result.exit_code == 0
    text = result.output
    assert "Example:\n" in text
    assert f"    simmer {command}" in text
    for typer_marks in ("<bool>", "<str>", "<path>", "<int", "{config", "--no-"):
        assert typer_marks not in text, typer_marks


def test_brackets_in_help_are_kept() -> None:
    result = CliRunner().invoke(app, ["console", "--help"], terminal_width=100)
    assert "([u0] -> [u0:15.45])" in " ".join(result.output.split())


def test_the_command_list_says_each_command_in_one_whole_line() -> None:
    result = CliRunner().invoke(app, ["--help"], terminal_width=80)
    lines = result.output.split("Commands:\n")[1].splitlines()
    listed = [line.split()[0] for line in lines if line.strip()]
    assert listed == COMMANDS  # one line each: nothing wrapped onto a line of its own
    assert not any(line.rstrip().endswith("...") for line in lines)


HEAVY = ("numba", "numpy", "pygame", "pydantic", "matplotlib", "av")


@pytest.mark.slow
@pytest.mark.parametrize("command", [[], ["run"], ["sweep"]])
def test_help_loads_nothing_heavy(command: list[str]) -> None:
    probe = (
        "import sys\n"
        "from simmer.cli import app\n"
        "try:\n"
        f"    app({[*command, '--help']!r}, prog_name='simmer')\n"
        "except SystemExit:\n"
        "    pass\n"
        f"print(sorted(m for m in {HEAVY!r} if m in sys.modules), file=sys.stderr)\n"
    )
    done = subprocess.run(
        [sys.executable, "-c", probe], capture_output=True, text=True, check=True, timeout=60
    )
    assert "Usage: simmer" in done.stdout
    assert done.stderr.strip() == "[]"


def test_the_event_types_and_the_client_load_no_compiler() -> None:
    probe = (
        "import sys, simmer.world.events, simmer.client;"
        f"print(sorted(m for m in {HEAVY!r} if m in sys.modules))"
    )
    done = subprocess.run(
        [sys.executable, "-c", probe], capture_output=True, text=True, check=True, timeout=60
    )
    assert done.stdout.strip() == "[]"
