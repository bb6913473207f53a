"""Every command of every docs page, as written, from a folder ``simmer new`` made outside the
repository, on ports that are not SimMeR's own (``SIMMER_PORTS``) while something else holds
61200-61202.

Each page's ``sh`` blocks are read in order. A command runs as a student's terminal would run
it (``simmer ...``, ``python ...``, ``cd``); one that opens a window and runs until it is closed
(``simmer run`` with no program, ``simmer replay``, ``simmer maze edit``) is started, waited for
(its start-up lines; a recording until it holds what a later command of the page reads), then a
program that the page runs "in another terminal" is run against it, and it is stopped with
Ctrl-C as a student would. Real processes, real sockets, a real (dummy-driver) window.

What a page takes for granted the walk stands in for, and says where (:data:`PAGES`): a page
with no ``simmer new`` of its own is walked from the folder ``simmer new`` makes; the original
SimMeR's ``config.py`` (the migrating page's reader has one); a TA's grading file, written from
the page's own example with team folders of the project's program; the real robot's
Bluetooth port, served by a second simulator's serial port (``simmer run --serial``). Pages
with no commands are named (:data:`NO_COMMANDS`), so that a page that gains some is walked too.

The walk keeps to each page's command lines; it makes the runs few where the pages say the
numbers are the reader's choice: a sweep file's ``seeds``, ``[sample]`` ``count`` and
``[grid]`` values (docs/lab1.md: "edit them to sweep your own settings"; docs/sweeps: "seeds: a
count or a list"), and a grading file's scenarios ("what the TA picks on the day")."""

from __future__ import annotations

import contextlib
import csv
import json
import os
import re
import shlex
import shutil
import signal
import socket
import subprocess
import sys
import threading
import tomllib
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from pathlib import Path

import pytest

from grade_support import PYTHON

from helpers import REPO, SIMMER_PY, wait_for

DOCS = REPO / "docs"
STANDARD = (61200, 61201, 61202)
EXPECTED_FAILURE = {"simmer run project.toml --start 0,4": "cell [0, 4] is solid"}
"""A command a page shows failing, and what its one line says."""
ANSWERS = {"python project_delivery.py": "B2\n"}
"""What a student types at a program's prompt."""
ROBOT_PORT = "/dev/rfcomm0"
"""The robot's Bluetooth port as docs/calibration.md writes it (its table: a name per system);
the walk's robot is a second simulator, and its serial port stands in for it."""
MY_ROBOT = '''"""The team's own program, over the robot's serial port given on its command line."""
import sys

from simmer.client import connect

with connect(serial=sys.argv[1]) as robot:
    for message in ["u0,u1,u2,u3", "w0-4", "u0,u1,u2,u3", "w0--4", "u0,u1,u2,u3"]:
        print(message, robot.send(message))
        if message.startswith("w0"):
            robot.wait_idle()
'''
NO_COMMANDS = {
    "api.md", "architecture.md", "configuration.md", "devices.md", "gym.md", "limits.md",
    "link.md", "protocol.md", "security.md",
}  # fmt: skip
"""Pages (under docs/) with nothing to type in a terminal: reference, design, and pages whose
commands are inline in the prose and shown on the pages walked."""


def _original_config(terminal: Terminal) -> None:
    """The reader's ``config.py`` from the original SimMeR (its default configuration), at the
    placeholder path the page names and beside the folder's files."""
    for target in (terminal.cwd / "path" / "to" / "config.py", terminal.cwd / "config.py"):
        target.parent.mkdir(parents=True, exist_ok=True)
        shutil.copy(SIMMER_PY / "default_config.py", target)


def _grading_course(terminal: Terminal) -> None:
    """A TA's course folder (``simmer new --project`` made it: project.toml): the page's
    example grading file, on one scenario (the TA's choice), with two teams whose programs are
    the project's example (an interpreter every user may run when a box runs as root, as the
    page says)."""
    text = (DOCS / "grading.md").read_text(encoding="utf-8")
    grading = re.findall(r"```toml\n(.*?)```", text, flags=re.S)[0]
    grading = re.sub(r"(?m)^seeds = .*$", "seeds = [1]", grading)
    grading = re.sub(r'(?m)^"scenario.target" = .*$', '"scenario.target" = ["B1"]', grading)
    grading = grading.replace('"python3 -u robot.py"', json.dumps(f"{PYTHON} -u robot.py"))
    team = grading[grading.index("[[team]]") :]
    grading += "\n" + team.replace("1", "2")
    assert 'folder = "teams/team2"' in grading, grading
    (terminal.cwd / "GRADING.toml").write_text(grading, encoding="utf-8")
    for name in ("team1", "team2"):
        folder = terminal.cwd / "teams" / name
        folder.mkdir(parents=True)
        shutil.copy(terminal.cwd / "project_delivery.py", folder / "robot.py")


def _student_beside_the_grading_file(terminal: Terminal) -> None:
    """A student's folder beside the grading file the TA published: their robot.py."""
    folder = terminal.cwd / "my_team"
    folder.mkdir()
    shutil.copy(terminal.cwd / "project_delivery.py", folder / "robot.py")
    terminal.cwd = folder


def _team_robot(terminal: Terminal) -> None:
    """The team's configuration (``robot.toml``: their rover) and program (``my_robot.py``)."""
    shutil.copy(terminal.cwd / "my_rover.toml", terminal.cwd / "robot.toml")
    (terminal.cwd / "my_robot.py").write_text(MY_ROBOT, encoding="utf-8")


@dataclass(frozen=True)
class Page:
    """How a page is walked: what ``simmer new`` is given for it, and what the walk stands in
    for that the page takes for granted."""

    new: tuple[str, ...] = ()
    """Added to the page's ``simmer new`` (its own first block says so), or given to the one
    the walk runs for a page without one."""
    setup: Callable[[Terminal], None] | None = None
    """Files the page's reader has already, written into the folder before the first command."""
    before: dict[str, Callable[[Terminal], None]] = field(default_factory=dict)
    """Done before a command (by the command's text): where the page moves the reader."""
    robot: bool = False
    """Whether the page talks to the real robot: a second simulator serves its serial port."""


PAGES = {
    "lab1.md": Page(),
    "project.md": Page(("--project",)),
    "localization.md": Page(("--localization",)),
    "sweeps/README.md": Page(),
    "mazes.md": Page(),
    "migrating.md": Page(setup=_original_config),
    "grading.md": Page(
        ("--project",),
        setup=_grading_course,
        before={"simmer grade ../GRADING.toml --only .": _student_beside_the_grading_file},
    ),
    "calibration.md": Page(setup=_team_robot, robot=True),
}


def page_commands(page: str) -> list[str]:
    """The commands of a page's ``sh`` blocks, in order: continuation lines joined, comments
    and blank lines dropped."""
    text = (DOCS / page).read_text(encoding="utf-8")
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
    something else on this machine, the other worker's walk, is held all the same). Once the
    page is walked, nothing may have connected to the ports held here: every command went to
    ``SIMMER_PORTS``."""
    with contextlib.ExitStack() as stack:
        held = []
        for port in STANDARD:
            sock = stack.enter_context(socket.socket())
            with contextlib.suppress(OSError):
                sock.bind(("127.0.0.1", port))
                sock.listen()
                held.append(sock)
        yield
        for sock in held:
            sock.setblocking(False)
            with contextlib.suppress(BlockingIOError):
                peer, address = sock.accept()
                peer.close()
                raise AssertionError(f"a command connected to {sock.getsockname()} from {address}")


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
        self.words: dict[str, str] = {}
        """Words of the page that name something the walk stands in for."""

    def argv(self, command: str) -> list[str]:
        words = [self.words.get(word, word) for word in shlex.split(command)]
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


@contextlib.contextmanager
def _robot(terminal: Terminal) -> Iterator[None]:
    """The real robot, as the tests stand one in: a simulator of the team's robot serving its
    serial port (at a fixed name, ``--link``) on ports of its own; the page's port name
    becomes that port."""
    link = terminal.cwd.parent / "robot-port"
    env = {**terminal.env, "SIMMER_PORTS": _free_ports()}
    argv = [sys.executable, "-m", "simmer", "run", "robot.toml", "--headless", "--serial"]
    robot = Background([*argv, "--serial-link", str(link)], terminal.cwd, env)
    try:
        wait_for(lambda: link.exists() or robot.process.poll() is not None, "the robot", 600)
        assert robot.process.poll() is None, "\n".join(robot.lines)
        terminal.words[ROBOT_PORT] = str(link)
        yield
    finally:
        printout = robot.stop()
    assert "Traceback" not in printout, printout


def _shrink_sweep(path: Path) -> None:
    """A sweep file with few runs, as its page lets the reader choose: one seed, two draws, two
    values of each grid key; every start cell (``"all"``) one drawn start."""
    lines = []
    section = ""
    for original in path.read_text(encoding="utf-8").splitlines():
        line = original
        if line.startswith("["):
            section = line.split("#")[0].strip()
        key, _, value = line.partition(" = ")
        if key == "seeds":
            line = "seeds = 1"
        elif section == "[sample]" and key == "count":
            line = "count = 2"
        elif section == "[grid]" and value:
            values = tomllib.loads(f"v = {value}")["v"]
            if key == '"scenario.start"' and values == "all":
                values = ["random"]
            line = f"{key} = {json.dumps(values[:2] if isinstance(values, list) else values)}"
        lines.append(line)
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")
    assert tomllib.loads(path.read_text(encoding="utf-8"))


def _runs_until_closed(command: str) -> bool:
    words = shlex.split(command)
    if words[:2] == ["simmer", "replay"]:
        return "--check" not in words
    if words[:3] == ["simmer", "maze", "edit"]:
        return True
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
        or window.said("editing ")
        or window.process.poll() is not None
    )


def _window(terminal: Terminal, command: str, later: list[str], said: list[str]) -> int:
    """Run a command that runs until closed: wait for it, run the programs the page runs
    against it in another terminal, then Ctrl-C; how many of ``later`` it took."""
    window = terminal.start(command)
    wait_for(lambda: _started(window), command, 600)
    assert window.process.poll() is None, f"{command}\n" + "\n".join(window.lines)
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


def _command(
    terminal: Terminal, page: Page, command: str, later: list[str], said: list[str]
) -> int:
    """Run one command of the page as its reader would; how many of ``later`` it took too."""
    words = shlex.split(command)
    if words[0] == "cd":
        terminal.cwd = terminal.cwd / words[1]
        assert terminal.cwd.is_dir(), command
        return 0
    if command in page.before:
        page.before[command](terminal)
    if words[:2] == ["simmer", "new"]:
        command = shlex.join([*words, *[flag for flag in page.new if flag not in words]])
    if words[:2] == ["simmer", "sweep"]:
        _shrink_sweep(terminal.cwd / words[2])
    if "my_task1.py" in command and not (terminal.cwd / "my_task1.py").exists():
        # the student's own Task 1 program, which the page has them write from this one
        shutil.copy(terminal.cwd / "obstacle_avoidance.py", terminal.cwd / "my_task1.py")
    if _runs_until_closed(command) and command not in EXPECTED_FAILURE:
        return _window(terminal, command, later, said)
    done = terminal.run(command, ANSWERS.get(command, ""))
    output = done.stdout + done.stderr
    assert "Traceback" not in output, f"{command}\n{output}"
    if command in EXPECTED_FAILURE:
        assert done.returncode == 1, f"{command}\n{output}"
        assert EXPECTED_FAILURE[command] in output, output
    else:
        assert done.returncode == 0, f"{command} (in {terminal.cwd})\n{output}"
    said.append(output)
    return 0


def _walk(name: str, tmp_path: Path) -> list[str]:
    """Run every command of page ``name``; what each said, for the assertions."""
    page = PAGES[name]
    commands = page_commands(name)
    assert commands, name
    home = tmp_path / "work"
    home.mkdir()
    assert REPO not in home.parents
    terminal = Terminal(home, _free_ports())
    said: list[str] = []
    with contextlib.ExitStack() as stack:
        if shlex.split(commands[0])[:2] != ["simmer", "new"]:  # the reader has a folder already
            for command in (shlex.join(["simmer", "new", "mine", *page.new]), "cd mine"):
                _command(terminal, page, command, [], said)
            if page.setup is not None:
                page.setup(terminal)
            if page.robot:
                stack.enter_context(_robot(terminal))
        else:
            assert page.setup is None, name
            assert not page.robot, name
        index = 0
        while index < len(commands):
            command = commands[index]
            index += 1
            index += _command(terminal, page, command, commands[index:], said)
    return said


def test_every_page_with_commands_is_walked_and_the_others_have_none() -> None:
    """Every docs page with a command block is in :data:`PAGES`; every other is named in
    :data:`NO_COMMANDS` and has no line a reader would type (``simmer ...``, ``python ...``)
    in any code block: a page that gains commands is walked, not skipped."""
    pages = {path.relative_to(DOCS).as_posix() for path in DOCS.rglob("*.md")}
    walked = {page for page in pages if page_commands(page)}
    assert walked == set(PAGES)
    assert pages >= NO_COMMANDS
    for page in sorted(pages - walked):
        text = (DOCS / page).read_text(encoding="utf-8")
        typed = [
            line
            for block in re.findall(r"```[a-z]*\n(.*?)```", text, flags=re.S)
            for line in block.splitlines()
            if re.match(r"\s*(\$ )?(simmer|python3?) ", line)
        ]
        assert not typed, (page, typed)
        assert page in NO_COMMANDS or "/" in page, page  # generated summaries and reports


@pytest.mark.slow
@pytest.mark.timeout(2400)
@pytest.mark.parametrize("page", list(PAGES))
def test_every_command_of_the_page_runs_from_a_new_folder_on_other_ports(
    page: str, tmp_path: Path, ctrl_c: None
) -> None:
    with _standard_ports_held():
        said = _walk(page, tmp_path)
    assert said
