"""Process trees: telling whether a process is still the one that was running."""

from __future__ import annotations

import os
import subprocess
import sys

from simmer.proctree import still_running


def test_a_running_process_is_still_running_and_an_exited_one_is_not() -> None:
    child = subprocess.Popen([sys.executable, "-c", "input()"], stdin=subprocess.PIPE)
    running = still_running(child.pid)
    assert running()
    assert still_running(os.getpid())()
    child.communicate(b"\n")
    assert not running()  # exited and reaped: gone from /proc


def test_an_exited_process_not_yet_reaped_is_not_running() -> None:
    child = subprocess.Popen([sys.executable, "-c", "input()"], stdin=subprocess.PIPE)
    running = still_running(child.pid)
    assert child.stdin is not None
    child.stdin.close()  # it exits; until waited for, it is a zombie
    os.waitid(os.P_PID, child.pid, os.WEXITED | os.WNOWAIT)
    assert not running()
    child.wait()
