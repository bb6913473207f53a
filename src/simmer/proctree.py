"""A control program's whole process tree, found and stopped when its run ends.

A program is started in a session of its own (:mod:`simmer.lockstep`), and stopping the run
signals that session's process group. A child that starts a session of its own (``setsid``,
a daemon) leaves the group, and when its parent exits it is handed to the nearest *subreaper*
(else to init), where the simulator loses sight of it. So on Linux ``simmer run`` and each sweep
worker become subreapers (:func:`adopt_orphans`): every process a program starts stays their
descendant however it detaches, and :func:`stop_strays` ends those still running when the run
is over, by walking ``/proc``, and reaps what was handed to them. A process that embeds
:func:`simmer.serve.serve` (a test run, a notebook) is not made one, since it would have to
reap every orphan of its other children too; there a detached child whose parent has exited is
out of sight.

What escapes: on other systems (macOS, Windows) there is no subreaper and no ``/proc``, so only
the process group is stopped; a process started through another service (``systemd-run``, ``at``,
a terminal multiplexer's server already running) is that service's child, not the program's.
"""

from __future__ import annotations

import ctypes
import os
import signal
import sys
from collections.abc import Callable
from contextlib import suppress
from pathlib import Path

PR_SET_CHILD_SUBREAPER = 36
"""``prctl`` option (Linux 3.4 and later)."""
_adopting: list[bool] = []
"""Holds True once this process is a subreaper (then it reaps the orphans handed to it)."""


def adopt_orphans() -> bool:
    """Make this process the subreaper of its descendants (Linux): one whose parent exits is
    handed to it, not to init. Whether that worked. Only for a process that starts programs
    and nothing else it waits for (``simmer run``, a sweep worker): see the module doc."""
    if not sys.platform.startswith("linux"):
        return False
    try:
        libc = ctypes.CDLL(None, use_errno=True)
        adopted = bool(libc.prctl(PR_SET_CHILD_SUBREAPER, 1, 0, 0, 0) == 0)
    except (OSError, AttributeError):
        return False
    if adopted and not _adopting:
        _adopting.append(True)
    return adopted


def _stat_fields(stat: str) -> list[str]:
    """The fields of a ``/proc/PID/stat`` line after the process's name, from its state on
    (the name, in parentheses, may hold spaces and ")")."""
    return stat[stat.rfind(")") + 2 :].split()


def _parents(zombies: bool = False) -> dict[int, int]:
    """Every running process's parent (or every zombie's), from ``/proc`` (empty where there
    is none)."""
    parents = {}
    with suppress(OSError):
        for entry in os.scandir("/proc"):
            if not entry.name.isdigit():
                continue
            try:
                stat = Path(entry.path, "stat").read_text()
            except OSError:  # it exited meanwhile
                continue
            fields = _stat_fields(stat)
            if fields and (fields[0] == "Z") == zombies:  # Z: exited, to be reaped
                parents[int(entry.name)] = int(fields[1])
    return parents


def still_running(pid: int) -> Callable[[], bool]:
    """A check that process ``pid`` is still the one running now: by its start time in
    ``/proc``, as a pid may be reused once it has exited; where there is no ``/proc``, by
    being this process's parent."""
    stat = Path(f"/proc/{pid}/stat")

    def state_and_start(text: str) -> tuple[str, str]:
        fields = _stat_fields(text)
        return fields[0], fields[19]  # state (Z: exited), start time (clock ticks after boot)

    try:
        _, started = state_and_start(stat.read_text())
    except OSError:
        return lambda: os.getppid() == pid

    def running() -> bool:
        try:
            state, start = state_and_start(stat.read_text())
        except OSError:  # gone
            return False
        return state != "Z" and start == started

    return running


def descendants(pid: int | None = None) -> set[int]:
    """The running processes below ``pid`` (default: this process), from ``/proc``."""
    root = os.getpid() if pid is None else pid
    children: dict[int, list[int]] = {}
    for child, parent in _parents().items():
        children.setdefault(parent, []).append(child)
    found: set[int] = set()
    todo = [root]
    while todo:
        for child in children.get(todo.pop(), []):
            if child not in found:
                found.add(child)
                todo.append(child)
    return found


def stop_strays(before: set[int]) -> set[int]:
    """SIGKILL every descendant of this process that is not in ``before`` (those running
    before the program started), and reap those that are its children (and, in a subreaper,
    the orphans handed to it that exited by themselves); the ones stopped."""
    strays = descendants() - before
    for pid in strays:
        with suppress(ProcessLookupError, PermissionError):
            os.kill(pid, signal.SIGKILL)
    for pid in strays:  # a child handed to this subreaper: wait, or it stays a zombie
        with suppress(ChildProcessError, OSError):
            os.waitpid(pid, 0)
    if _adopting:
        me = os.getpid()
        for pid, parent in _parents(zombies=True).items():
            if parent == me and pid not in before:
                with suppress(ChildProcessError, OSError):
                    os.waitpid(pid, os.WNOHANG)
    return strays
