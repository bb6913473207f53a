"""Lockstep runs: a control program and the simulation share one simulated clock.

``simmer run CONFIG --program "python my_robot.py"`` starts the program itself (see
:class:`Program`), as written: ``python`` is the one first on the student's ``PATH``, with
their environment's packages, not SimMeR's own. This package's ``gate`` and ``shim`` folders
go first on its ``PYTHONPATH``: the gate stops a Python older than ``OLDEST_PYTHON`` with
one plain line, and the shim's ``sitecustomize`` (standard library only, Python 3.8 and later)
makes the program's ``time.sleep`` and clock reads follow simulated time and sends its
connections to SimMeR's standard ports to this run's free ports. A process the program starts
is not on the clock: the shim refuses its sleeps and its connections to the simulator.

The simulator then advances only when the program asks (a sleep, or a clock read after many
with nothing between) and by a fixed link delay per message, so the same configuration, seed
and program give the same run on any machine and at any speed.

The clock messages, on the persistent protocol (one line each, answered with a one-value frame
holding the simulated time after it, as float64):

* ``!sleep S``: advance the clock by S seconds, answer when the simulation has got there;
* ``!idle``: advance until no drive is moving (at most 600 simulated seconds);
* ``!time``: the clock, without advancing it; but the :data:`FREE_TIME_READS`-th read in a row
  with no message or sleep between advances it by one step, so a program that busy-waits on
  the clock still progresses.
"""

from __future__ import annotations

import os
import shlex
import shutil
import signal
import subprocess
import time
from collections.abc import Mapping, Sequence
from contextlib import suppress
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

from simmer.errors import ProgramNotFound

if TYPE_CHECKING:
    from simmer.lockstep.box import Box
from simmer.lockstep.gate.sitecustomize import OLDEST_PYTHON as OLDEST_PYTHON
from simmer.ports import PORT_RX, PORT_TX, PORTS_VARIABLE, STREAM_PORT

SHIM = Path(__file__).resolve().parent / "shim"
"""The folder whose ``sitecustomize.py`` puts a Python program on the simulated clock."""
GATE = Path(__file__).resolve().parent / "gate"
"""The folder before :data:`SHIM` on the path, whose ``sitecustomize.py`` (parsed by every
Python) stops a Python older than ``OLDEST_PYTHON`` (3.8, defined there) with one line, else
hands over to the shim."""

FREE_TIME_READS = 16
"""Clock reads in a row that cost nothing; the next one advances one step (see module doc).
Generous enough that a library's own reads inside one blocking call (pyserial reads the clock
a few times per ``read``) never advance time, so a run does not depend on how data arrived."""

STANDARD_PORTS = {"port_rx": PORT_RX, "port_tx": PORT_TX, "stream": STREAM_PORT}
"""SimMeR's standard ports, which a lockstep program's connections are redirected from."""

MAX_ANSWER = 4096
"""Characters of ``--answer``: a few typed lines, well inside a pipe's buffer (so writing them
never waits for the program to read)."""

EXIT_SECONDS = 3
"""``simmer run --program`` exit status when the ``--seconds`` limit of simulated time ended it."""
EXIT_TIMEOUT = 124
"""Exit status when the wall-clock ``--timeout`` ended it (as coreutils ``timeout`` does)."""


def program_environment(
    ports: Mapping[str, int],
    host: str = "127.0.0.1",
    base: Mapping[str, str] | None = None,
    configured: Mapping[str, int] | None = None,
) -> dict[str, str]:
    """The environment a lockstep program runs in: the gate and the shim first on its
    ``PYTHONPATH``, this run's ports, ``PYTHONUNBUFFERED``; everything else (``PATH``, a
    virtual environment) as ``base`` has it (default: this process's environment).

    ``ports`` maps ``port_rx``, ``port_tx`` and ``stream`` to the ports this run serves on;
    connections to SimMeR's standard ports, and to the ports the configuration names
    (``configured``, same keys), are sent there. ``simmer.client`` reads ``SIMMER_HOST``,
    ``SIMMER_PORT``, ``SIMMER_PORT_RX`` and ``SIMMER_PORT_TX`` (and ``SIMMER_PORTS``, set to
    all three, as the examples' raw sockets do); the shim reads
    ``SIMMER_LOCKSTEP``, ``SIMMER_PORT_MAP``, ``SIMMER_MESSAGE_PORTS`` and
    ``SIMMER_REPLY_PORTS``.
    """
    env = dict(os.environ if base is None else base)
    path = env.get("PYTHONPATH")
    env["PYTHONPATH"] = os.pathsep.join([str(GATE), str(SHIM), *([path] if path else [])])
    env["SIMMER_LOCKSTEP"] = f"{host}:{ports['stream']}"
    env["SIMMER_EPOCH"] = repr(time.time())
    redirected = {STANDARD_PORTS[name]: port for name, port in ports.items()}
    for name, port in (configured or {}).items():
        redirected.setdefault(port, ports[name])
    env["SIMMER_PORT_MAP"] = ",".join(f"{old}={new}" for old, new in redirected.items())
    env["SIMMER_MESSAGE_PORTS"] = f"{ports['port_rx']},{ports['stream']}"
    env["SIMMER_REPLY_PORTS"] = str(ports["port_tx"])
    env["SIMMER_HOST"] = host
    env["SIMMER_PORT"] = str(ports["stream"])
    env["SIMMER_PORT_RX"] = str(ports["port_rx"])
    env["SIMMER_PORT_TX"] = str(ports["port_tx"])
    env[PORTS_VARIABLE] = f"{ports['port_rx']},{ports['port_tx']},{ports['stream']}"
    env["PYTHONUNBUFFERED"] = "1"  # the program's printout appears as it happens
    return env


def split_command(command: str | Sequence[str], path: str | None = None) -> list[str]:
    """A program's command line as arguments, to run as written: a first word without a
    folder (``python``, ``py``, ``node``) becomes the file a terminal would run, the first of
    that name on ``path`` (the run's ``PATH``; None: this process's), left as it is if there is
    none. So ``python`` is the student's, with their environment's packages, never SimMeR's
    own (which Windows would otherwise look in first, as the starting program's folder)."""
    args = _arguments(command)
    found = on_path(args[0], path)
    if found is not None:
        args[0] = found
    return args


def _arguments(command: str | Sequence[str]) -> list[str]:
    args = (
        shlex.split(command, posix=os.name != "nt") if isinstance(command, str) else list(command)
    )
    if not args:
        raise ValueError("the program's command line is empty")
    return args


def on_path(name: str, path: str | None = None) -> str | None:
    """The file that runs as ``name`` when ``name`` has no folder (the first of that name on
    ``path``; None: this process's ``PATH``), else None (a path, or a name not found)."""
    if not name or os.path.basename(name) != name:
        return None
    return shutil.which(name, path=path)


def which_program(command: str | Sequence[str]) -> str:
    """The command as given, and the file its first word runs if that was found on ``PATH``
    (``python my_robot.py (python: /home/me/.venv/bin/python)``): which Python runs it."""
    shown = command if isinstance(command, str) else shlex.join(command)
    try:
        name = _arguments(command)[0]
    except ValueError:  # not a command line Program.start can run; it says so
        return shown
    found = on_path(name)
    return shown if found is None else f"{shown} ({name}: {found})"


def runs_python(command: str | Sequence[str]) -> bool:
    """Whether ``command`` starts a Python program (which the shim puts on the simulated
    clock): a Python interpreter, a ``.py`` file, or a script whose ``#!`` line names Python."""
    args = split_command(command)
    name = Path(args[0]).name.lower()
    if name.startswith(("python", "pypy")) or name in ("py", "py.exe") or name.endswith(".py"):
        return True
    try:
        with open(args[0], "rb") as file:
            return b"python" in file.readline(200)
    except OSError:
        return False


NOT_PYTHON = (
    "note: {command!r} does not look like a Python program, so SimMeR cannot put its sleeps on "
    "the simulated clock: the clock advances only by its messages (one step each) and by the "
    "clock messages it sends. To make its runs repeatable, see 'Clock messages' in "
    "docs/protocol.md."
)
"""What ``simmer run --program`` says for a program :func:`runs_python` does not recognise."""


@dataclass
class Program:
    """A control program started for a run, in a session of its own so that the whole process
    tree can be stopped; its standard input, output and error are the run's own."""

    process: subprocess.Popen[bytes]

    @classmethod
    def start(
        cls,
        command: str | Sequence[str],
        env: Mapping[str, str],
        answer: str | None = None,
        *,
        folder: Path | None = None,
        output: int | None = None,
        box: Box | None = None,
        ports: Sequence[int] = (),
    ) -> Program:
        """Start ``command`` (raises ``OSError`` if it cannot be started:
        :class:`~simmer.errors.ProgramNotFound` if its first word is on no folder of ``PATH``).
        With ``answer``, its standard input is that text and a newline, then its end
        (``--answer``: what a person would type at the program's prompt). It works in
        ``folder`` and writes its standard output and error to the file descriptor ``output``
        (None: this process's folder and output), so that a sweep worker gives each run's
        program its own without changing its own. With ``box`` it runs in that box
        (:mod:`simmer.lockstep.box`: its folder is the box's copy, ``ports`` the only ones it
        may connect to)."""
        if answer is not None and len(answer) > MAX_ANSWER:
            raise OSError(f"--answer is {len(answer):,} characters; at most {MAX_ANSWER:,}")
        args = split_command(command, env.get("PATH"))
        if os.path.basename(args[0]) == args[0]:  # a name on_path did not find
            raise ProgramNotFound(
                f"cannot start the program: no {args[0]!r} on this terminal's PATH. Activate "
                "the environment it runs in (SimMeR's: the README's Quick start), or give its "
                "full path in --program"
            )
        if box is not None:
            from simmer.lockstep.box import box_environment, boxed_command

            args, env, folder = (
                boxed_command(args, box, list(ports)),
                box_environment(env, box),
                box.work,
            )
        process = subprocess.Popen(
            args,
            env=dict(env),
            pass_fds=box.network.namespaces if box is not None and box.network else (),
            start_new_session=True,
            cwd=folder,
            stdin=None if answer is None else subprocess.PIPE,
            stdout=output,
            stderr=output,
        )
        if process.stdin is not None:  # fits the pipe's buffer: never waits for the program
            with process.stdin:
                process.stdin.write((answer or "").encode("utf-8") + b"\n")
        return cls(process)

    def wait(self, timeout: float | None = None) -> int | None:
        """The exit status once the program has exited (None if still running at ``timeout``)."""
        try:
            return self.process.wait(timeout)
        except subprocess.TimeoutExpired:
            return None

    def stop(self, grace: float = 2.0) -> int:
        """Stop the program and everything it started: SIGTERM, then SIGKILL after ``grace`` s."""
        if self.process.poll() is None:
            self._signal(kill=False)
            if self.wait(grace) is None:
                self._signal(kill=True)
        self._signal(kill=True)  # children left behind by a program that exited
        return self.process.wait()

    def _signal(self, *, kill: bool) -> None:
        if os.name == "nt":  # no process groups there: stop the program itself
            with suppress(OSError):
                self.process.kill() if kill else self.process.terminate()
            return
        with suppress(ProcessLookupError, PermissionError):
            os.killpg(self.process.pid, signal.SIGKILL if kill else signal.SIGTERM)
