"""``simmer run --program "python x.py"`` runs the student's own Python (issue 30, item 4): the
``python`` first on their PATH, with their environment's packages, not SimMeR's. The shim it
loads needs only the standard library and Python 3.8; an older Python gets one plain line.

The interpreters are pyenv's where the machine has them (a test skips, saying which, where it
does not); the static checks run everywhere."""

from __future__ import annotations

import ast
import os
import subprocess
import sys
import sysconfig
from pathlib import Path

import pytest
from typer.testing import CliRunner

from simmer.cli import app
from simmer.errors import ProgramNotFound
from simmer.lockstep import (
    GATE,
    OLDEST_PYTHON,
    SHIM,
    Program,
    program_environment,
    split_command,
)

from helpers import REPO, run_simmer

pytestmark = pytest.mark.timeout(180)

PYENV = Path("/root/.pyenv/versions")


def interpreter(version: str) -> Path:
    """pyenv's Python ``version`` (e.g. "3.8"), or skip the test saying it is not here."""
    found = sorted(PYENV.glob(f"{version}.*/bin/python"))
    if not found:
        pytest.skip(f"no Python {version} on this machine (looked in {PYENV}/{version}.*)")
    return found[-1]


PLAIN_SOCKETS = """\
import socket, struct, sys, time

def ask(robot, message):
    robot.sendall(message + b"\\n")
    width, count = struct.unpack("<BH", robot.recv(3))
    data = b""
    while len(data) < width * count:
        data += robot.recv(width * count - len(data))
    return struct.unpack("<" + ("d" if width == 8 else "f") * count, data)

print("python", "%d.%d" % sys.version_info[:2])
robot = socket.create_connection(("127.0.0.1", 61202))
print("u0", ask(robot, b"u0"))
for _ in range(3):
    with socket.create_connection(("127.0.0.1", 61200)) as out:
        out.sendall(b"w0-2")
    time.sleep(0.5)
    with socket.create_connection(("127.0.0.1", 61201)) as back:
        print("reply", len(back.recv(64)), "bytes")
print("clock", round(time.monotonic(), 3))
"""
"""A student's program with plain sockets: the persistent port, then the two-port scheme,
sleeping between a move and its reply."""


@pytest.mark.slow
@pytest.mark.parametrize("version", ["3.8", "3.13"])
def test_a_plain_socket_program_runs_on_the_clock_in_its_own_python(
    version: str, tmp_path: Path
) -> None:
    python = interpreter(version)
    (tmp_path / "robot.py").write_text(PLAIN_SOCKETS, encoding="utf-8")
    done = run_simmer(
        "run", "--headless", "--seconds", "30", "--program", f"{python} robot.py", cwd=tmp_path
    )
    assert done.returncode == 0, done.stdout + done.stderr
    printed = done.stdout.split(f"starting the program: {python} robot.py\n")[1]
    lines = printed.splitlines()
    assert lines[:2] == [f"python {version}", "u0 (39.5,)"], done.stdout + done.stderr
    assert lines[2:5] == ["reply 4 bytes"] * 3
    assert lines[5] == "clock 1.567"  # three sleeps of 0.5 s and four messages of a step
    assert "run ended: the program exited with status 0" in done.stdout
    assert done.stderr == ""


@pytest.mark.parametrize("version", ["2.7", "3.6", "3.7"])
def test_an_older_python_is_stopped_with_one_plain_line(version: str) -> None:
    python = interpreter(version)
    env = program_environment({"port_rx": 1, "port_tx": 2, "stream": 3})
    done = subprocess.run(
        [python, "-c", "print('ran off the clock')"],
        env=env, capture_output=True, text=True, timeout=60, check=False,
    )  # fmt: skip
    assert done.returncode == 2
    assert done.stdout == ""  # the program never ran
    (line,) = done.stderr.splitlines()
    assert line.startswith(f"SimMeR: this program runs on Python {version}.")
    assert "needs Python 3.8 or later (OLDEST_PYTHON)" in line
    assert "PATH" in line


@pytest.mark.slow
def test_a_run_on_python_3_7_ends_with_the_line_and_the_programs_status(tmp_path: Path) -> None:
    python = interpreter("3.7")
    (tmp_path / "robot.py").write_text(PLAIN_SOCKETS, encoding="utf-8")
    done = run_simmer(
        "run", "--headless", "--seconds", "30", "--program", f"{python} robot.py", cwd=tmp_path
    )
    assert done.returncode == 2, done.stdout + done.stderr
    (line,) = done.stderr.splitlines()
    assert line.startswith("SimMeR: this program runs on Python 3.7.")
    assert "Traceback" not in done.stdout + done.stderr
    assert "run ended: the program exited with status 2" in done.stdout


def test_the_shim_is_python_3_8_and_the_gate_parses_everywhere() -> None:
    """Static: the shim's syntax with Python 3.8's grammar, and vermin's verdict on the
    versions the shim's modules and syntax need (the runs above need the interpreters)."""
    assert OLDEST_PYTHON == (3, 8)
    shim = SHIM / "sitecustomize.py"
    ast.parse(shim.read_text(encoding="utf-8"), str(shim), feature_version=OLDEST_PYTHON)
    assert minimum_versions(shim)[1] <= OLDEST_PYTHON, "the shim needs a newer Python"
    gate = GATE / "sitecustomize.py"
    assert minimum_versions(gate) == ((2, 0), (3, 0))  # parsed and run by any Python 2 and 3
    imports = {
        alias.name.split(".")[0]
        for node in ast.walk(ast.parse(shim.read_text(encoding="utf-8")))
        if isinstance(node, ast.Import | ast.ImportFrom)
        for alias in (node.names if isinstance(node, ast.Import) else [ast.alias(node.module)])
    }
    assert imports <= sys.stdlib_module_names  # needs nothing installed in the environment


def minimum_versions(path: Path) -> tuple[tuple[int, ...], tuple[int, ...]]:
    """vermin's minimum Python 2 and 3 versions for ``path`` ((0,): cannot run there)."""
    vermin = Path(sysconfig.get_path("scripts")) / "vermin"
    done = subprocess.run(
        [vermin, "--no-tips", "--format", "parsable", str(path)],
        capture_output=True, text=True, timeout=60, check=False,
    )  # fmt: skip
    assert done.returncode == 0, done.stdout + done.stderr
    *_, two, three, _feature = done.stdout.splitlines()[-1].split(":")
    return tuple(map(number, two.split("."))), tuple(map(number, three.split(".")))


def number(part: str) -> int:
    return 0 if part in ("!2", "!3", "~2", "~3") else int(part.lstrip("~"))


def test_python_is_the_first_on_the_runs_path(tmp_path: Path) -> None:
    mine = tmp_path / "mine"
    mine.mkdir()
    for name in ("python", "python3"):
        (mine / name).write_text("#!/bin/sh\n", encoding="utf-8")
        (mine / name).chmod(0o755)
    path = os.pathsep.join([str(mine), os.environ["PATH"]])
    assert split_command("python robot.py", path) == [str(mine / "python"), "robot.py"]
    assert split_command(["python3", "-u", "x y.py"], path) == [
        str(mine / "python3"),
        "-u",
        "x y.py",
    ]
    assert split_command(f"{sys.executable} robot.py", path)[0] == sys.executable
    assert split_command("./robot.py", path)[0] == "./robot.py"  # a path: as written
    assert split_command("no-such-program", path)[0] == "no-such-program"
    with pytest.raises(ProgramNotFound, match="no 'no-such-program' on this terminal's PATH"):
        Program.start("no-such-program x.py", {"PATH": path})


ONLY_HERE = """\
import only_in_my_environment

print(only_in_my_environment.GREETING)
"""


@pytest.mark.slow
def test_a_program_imports_a_package_that_only_the_students_environment_has(
    tmp_path: Path,
) -> None:
    venv = tmp_path / "my env"  # a space, as in many students' paths
    subprocess.run([sys.executable, "-m", "venv", "--without-pip", venv], check=True, timeout=120)
    scripts = venv / ("Scripts" if os.name == "nt" else "bin")
    site = subprocess.run(
        [scripts / "python", "-c", "import sysconfig; print(sysconfig.get_path('purelib'))"],
        capture_output=True, text=True, check=True, timeout=60,
    ).stdout.strip()  # fmt: skip
    Path(site, "only_in_my_environment.py").write_text("GREETING = 'hello from my env'\n")
    (tmp_path / "robot.py").write_text(ONLY_HERE, encoding="utf-8")
    env = {**os.environ, "PATH": os.pathsep.join([str(scripts), os.environ["PATH"]])}
    done = subprocess.run(
        [sys.executable, "-m", "simmer", "run", "--headless", "--seconds", "10",
         "--program", "python robot.py"],
        cwd=tmp_path, env=env, capture_output=True, text=True, timeout=120, check=False,
    )  # fmt: skip
    assert done.returncode == 0, done.stdout + done.stderr
    assert f"starting the program: python robot.py (python: {scripts / 'python'})" in done.stdout
    assert "hello from my env\n" in done.stdout
    assert "ModuleNotFoundError" not in done.stderr


def test_run_help_says_what_program_does_to_the_environment() -> None:
    result = CliRunner().invoke(app, ["run", "--help"], terminal_width=200)
    said = " ".join(result.output.split())
    for words in ("first on your PATH", "Python 3.8 or later", "PYTHONPATH", "SIMMER_*",
                  "PYTHONUNBUFFERED=1", "may not sleep or talk to the simulator"):  # fmt: skip
        assert words in said, words


def test_the_docs_say_it_too() -> None:
    said = " ".join((REPO / "docs" / "protocol.md").read_text(encoding="utf-8").split())
    for words in ("Python 3.8 or later", "PYTHONPATH", "SIMMER_PROGRAM_PID", "PYTHONUNBUFFERED"):
        assert words in said, words
