"""Every command of the pages a student follows (docs/lab1.md, project.md, localization.md),
as written, from a folder ``simmer new`` made outside the repository, on ports that are not
SimMeR's own (``SIMMER_PORTS``) while something else holds 61200-61202.

Each page's ``sh`` blocks are read in order. A command runs as a student's terminal would run
it (``simmer ...``, ``python ...``, ``cd``); one that opens a window and runs until it is closed
(``simmer run`` with no program, ``simmer replay``) is started, waited for (its start-up lines;
a recording until it holds what a later command of the page reads), then a program that the
page runs "in another terminal" is run against it, and it is stopped with Ctrl-C as a student
would. Real processes, real sockets, a real (dummy-driver) window."""

from __future__ import annotations

import contextlib
import csv
import os
import re
import shlex
import shutil
import signal
import socket
import subprocess
import sys
import threading
from collections.abc import Iterator
from pathlib import Path

import pytest

from helpers import REPO, wait_for

PAGES = {"lab1.md": (), "project.md": ("--project",), "localization.md": ("--localization",)}
"""Each page, and what ``simmer new`` is given for it (the page's own first block says so)."""
EXPECTED_FAILURE = {"simmer run project.toml --start 0,4": "cell [0, 4] is solid"}
"""A command the page shows failing, and what its one line says."""
ANSWERS = {"python project_delivery.py": "B2\n"}
"""What a student types at a program's prompt."""
STANDARD = (61200, 61201, 61202)


def page_commands(page: str) -> list[str]:
    """The commands of a page's ``sh`` blocks, in order: continuation lines joined, comments
    and blank lines dropped."""
    text = (REPO / "docs" / page).read_text(encoding="utf-8")
    commands = []
    for block in re.findall(r"```sh\n(.*?)```", text, flags=re.S):
        for line in block.replace("\\\n", " ").splitlines():
            words = shlex.split(line, comments=True)
            if words:
                commands.append(shlex.join(words))
    return commands


def _free_ports() -> str:
    """Three ports free now, none of SimMeR's own, as ``SIMMER_PORTS`` names them."""
    with contextlib.ExitStack() as stack:
        socks = [stack.enter_context(socket.socket()) for _ in range(3)]
        for sock in socks:
            sock.bind(("127.0.0.1", 0))
        ports = [sock.getsockname()[1] for sock in socks]
    assert not set(ports) & set(STANDARD)
    return ",".join(map(str, ports))


@contextlib.contextmanager
def _standard_ports_held() -> Iterator[None]:
    """Another simulator on 61200-61202: listening sockets there (a port already held by
    something else on this machine is held all the same)."""
    with contextlib.ExitStack() as stack:
        for port in STANDARD:
            sock = stack.enter_context(socket.socket())
            with contextlib.suppress(OSError):
                sock.bind(("127.0.0.1", port))
                sock.listen()
        yield


class Terminal:
    """A folder and an environment, as a student's terminal: runs commands there."""

    def __init__(self, home: Path, ports: str) -> None:
        self.cwd = home
        bin_dir = str(Path(sys.executable).parent)
        self.env = {
            **os.environ,
            "PATH": bin_dir + os.pathsep + os.environ.get("PATH", ""),
            "SIMMER_PORTS": ports,
            "SDL_VIDEODRIVER": "dummy",
            "SDL_AUDIODRIVER": "dummy",
        }
        for name in ("SIMMER_PORT", "SIMMER_PORT_RX", "SIMMER_PORT_TX", "SIMMER_HOST"):
            self.env.pop(name, None)

    def argv(self, command: str) -> list[str]:
        words = shlex.split(command)
        if words[0] == "simmer":
            return [sys.executable, "-m", "simmer", *words[1:]]
        if words[0] == "python":
            return [sys.executable, *words[1:]]
        raise AssertionError(f"a command the walk does not know: {command}")

    def run(self, command: str, stdin: str = "") -> subprocess.CompletedProcess[str]:
        return subprocess.run(
            self.argv(command), cwd=self.cwd, env=self.env, input=stdin, capture_output=True,
            text=True, encoding="utf-8", errors="replace", timeout=900, check=False,
        )  # fmt: skip

    def start(self, command: str) -> Background:
        return Background(self.argv(command), self.cwd, self.env)


class Background:
    """A command that runs until stopped (a window), its printout collected."""

    def __init__(self, argv: list[str], cwd: Path, env: dict[str, str]) -> None:
        self.lines: list[str] = []
        self.process = subprocess.Popen(
            argv, cwd=cwd, env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
            text=True, encoding="utf-8", errors="replace",
        )  # fmt: skip
        self._reader = threading.Thread(target=self._read, daemon=True)
        self._reader.start()

    def _read(self) -> None:
        assert self.process.stdout is not None
        for line in self.process.stdout:
            self.lines.append(line.rstrip("\n"))

    def said(self, text: str) -> bool:
        return any(text in line for line in list(self.lines))

    def stop(self) -> str:
        """Ctrl-C, as a student ends it; its whole printout."""
        if self.process.poll() is None:
            self.process.send_signal(signal.SIGINT)
        self.process.wait(timeout=120)
        self._reader.join(timeout=60)
        assert self.process.stdout is not None
        self.process.stdout.close()
        return "\n".join(self.lines)


def _runs_until_closed(command: str) -> bool:
    words = shlex.split(command)
    if words[:2] == ["simmer", "replay"]:
        return "--check" not in words
    return words[:2] == ["simmer", "run"] and "--program" not in words


def _trace_seconds(folder: Path) -> float:
    try:
        with (folder / "trace.csv").open(encoding="utf-8") as file:
            rows = list(csv.DictReader(file))
    except FileNotFoundError:
        return 0.0
    return float(rows[-1]["time"]) if rows else 0.0


def _needed_seconds(command: str, later: list[str]) -> float:
    """How much simulated time a recorded window run must hold for the page's later commands
    (``simmer render DIR --to T``)."""
    words = shlex.split(command)
    if "--record" not in words:
        return 0.0
    folder = words[words.index("--record") + 1]
    needed = 0.0
    for other in later:
        more = shlex.split(other)
        if more[:3] == ["simmer", "render", folder] and "--to" in more:
            needed = max(needed, float(more[more.index("--to") + 1]) + 0.5)
    return needed


def _started(window: Background) -> bool:
    return (
        window.said("persistent TCP")
        or window.said("re-simulating")
        or window.process.poll() is not None
    )


def _window(terminal: Terminal, command: str, later: list[str], said: list[str]) -> int:
    """Run a command that runs until closed: wait for it, run the programs the page runs
    against it in another terminal, then Ctrl-C; how many of ``later`` it took."""
    window = terminal.start(command)
    wait_for(lambda: _started(window), command, 600)
    words = shlex.split(command)
    if words[1] == "run":
        stream_port = terminal.env["SIMMER_PORTS"].split(",")[2]
        assert window.said(f"port {stream_port} "), "\n".join(window.lines)
    needed = _needed_seconds(command, later)
    if needed:
        folder = terminal.cwd / words[words.index("--record") + 1]
        wait_for(lambda: _trace_seconds(folder) >= needed, f"{command}: {needed} s", 600)
    taken = 0
    for other in later:
        if not other.startswith("python "):
            break
        done = terminal.run(other, ANSWERS.get(other, ""))
        assert done.returncode == 0, f"{other}\n{done.stdout}{done.stderr}"
        said.append(done.stdout)
        taken += 1
    printout = window.stop()
    assert "Traceback" not in printout, f"{command}\n{printout}"
    said.append(printout)
    return taken


def _walk(page: str, tmp_path: Path) -> list[str]:
    """Run every command of ``page``; what each said, for the assertions."""
    commands = page_commands(page)
    assert commands, page
    home = tmp_path / "work"
    home.mkdir()
    assert REPO not in home.parents
    terminal = Terminal(home, _free_ports())
    said: list[str] = []
    index = 0
    while index < len(commands):
        command = commands[index]
        index += 1
        words = shlex.split(command)
        if words[0] == "cd":
            terminal.cwd = terminal.cwd / words[1]
            assert terminal.cwd.is_dir(), command
            continue
        if words[:2] == ["simmer", "new"]:
            command = shlex.join([*words, *[flag for flag in PAGES[page] if flag not in words]])
        if "my_task1.py" in command and not (terminal.cwd / "my_task1.py").exists():
            # the student's own Task 1 program, which the page has them write from this one
            shutil.copy(terminal.cwd / "obstacle_avoidance.py", terminal.cwd / "my_task1.py")
        if _runs_until_closed(command) and command not in EXPECTED_FAILURE:
            taken = _window(terminal, command, commands[index:], said)
            index += taken
            continue
        done = terminal.run(command, ANSWERS.get(command, ""))
        output = done.stdout + done.stderr
        assert "Traceback" not in output, f"{command}\n{output}"
        if command in EXPECTED_FAILURE:
            assert done.returncode == 1, f"{command}\n{output}"
            assert EXPECTED_FAILURE[command] in output, output
        else:
            assert done.returncode == 0, f"{command} (in {terminal.cwd})\n{output}"
        said.append(output)
    return said


@pytest.mark.slow
@pytest.mark.timeout(2400)
@pytest.mark.parametrize("page", list(PAGES))
def test_every_command_of_the_page_runs_from_a_new_folder_on_other_ports(
    page: str, tmp_path: Path, ctrl_c: None
) -> None:
    with _standard_ports_held():
        said = _walk(page, tmp_path)
    assert said
