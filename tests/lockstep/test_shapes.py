"""Every shape of program gives the same run every time (issue 30): a thread that polls the
reply port while the main thread sleeps, a busy-wait on a serial port's ``in_waiting``, a
library that reads the clock, ``select``, ``poll``/``epoll`` and socket timeouts, an
``asyncio`` client. Each is
written the way students write them (plain sockets or pyserial), run five times under
``simmer run --program --record``, two of them beside a CPU-burning process, and every run
must record the same events and trace and print the same thing."""

from __future__ import annotations

import json
import subprocess
import sys
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

import pytest

from link_support import run_program
from simmer import Simulation

from helpers import REPO, make_config, noisy_data

pytestmark = [pytest.mark.slow, pytest.mark.timeout(600)]

SHAPES = REPO / "tests" / "fixtures" / "shapes"
V10 = {"reply_bytes": 8}
V11 = {"reply_bytes": 4}
V12 = {"protocol": "framed", "str_encoding": "ascii"}


@contextmanager
def cpu_burning() -> Iterator[None]:
    """Another process keeping a CPU busy meanwhile."""
    hog = subprocess.Popen([sys.executable, "-c", "while True: pass"])
    try:
        yield
    finally:
        hog.kill()
        hog.wait()


def recorded_run(
    folder: Path,
    program: str,
    config: dict[str, Any],
    capfd: pytest.CaptureFixture[str],
    **options: Any,
) -> tuple[str, str, str]:
    """One ``--program`` run, recorded into ``folder``: its events (the client's port, which
    the operating system chooses, left out), its trace and what the program printed."""
    sim = Simulation(make_config(noisy_data() | config), seed=11)
    served = run_program(sim, f"{sys.executable} {program}", record=folder, **options)
    printed = capfd.readouterr()
    assert (served.ended_by, served.exit_status) == ("program", 0), printed.err
    events = []
    for line in (folder / "events.jsonl").read_text(encoding="utf-8").splitlines():
        event = json.loads(line)
        if "client" in event:
            event["client"] = event["client"].split(" ")[0]
        events.append(json.dumps(event, sort_keys=True))
    trace = (folder / "trace.csv").read_text(encoding="utf-8")
    return "\n".join(events), trace, printed.out


def five_runs(
    tmp_path: Path,
    program: str,
    config: dict[str, Any],
    capfd: pytest.CaptureFixture[str],
    **options: Any,
) -> tuple[str, str, str]:
    """Five recorded runs, the last two beside a CPU-burning process; all must be the same.
    The first run's events, trace and printout."""
    runs = []
    for index in range(5):
        if index < 3:
            runs.append(recorded_run(tmp_path / f"run{index}", program, config, capfd, **options))
        else:
            with cpu_burning():
                runs.append(
                    recorded_run(tmp_path / f"run{index}", program, config, capfd, **options)
                )
    for index, run in enumerate(runs[1:], 1):
        for what, first, other in zip(("events", "trace", "printout"), runs[0], run, strict=True):
            assert other == first, f"run {index}'s {what} differs from run 0's"
    return runs[0]


def test_a_thread_polling_the_reply_port_while_the_main_thread_sleeps(
    tmp_path: Path, capfd: pytest.CaptureFixture[str]
) -> None:
    # The original v1.0 lab's dead_reckoning.py: the main thread's sleep returns only once
    # the thread has stored the reply, so each reading is the one its message asked for.
    _events, _trace, printed = five_runs(tmp_path, str(SHAPES / "reply_thread.py"), V10, capfd)
    lines = printed.splitlines()
    assert lines[0].startswith("Ultrasonic 0 reading:")
    assert lines[0].endswith("(1 replies)")  # stored before the sleep returned
    assert lines[1] == "Drive reply: inf"
    assert lines[-1].startswith("done")


def test_a_busy_wait_on_a_serial_ports_in_waiting(
    tmp_path: Path, capfd: pytest.CaptureFixture[str]
) -> None:
    # The stock v1.2 client's receive loop: each reply is seen by the first in_waiting after
    # it, whatever the machine's speed, so each costs the same simulated time every run.
    _events, _trace, printed = five_runs(
        tmp_path, str(SHAPES / "serial_busy_wait.py"), V12, capfd, serial=True
    )
    lines = printed.splitlines()
    assert lines[0].startswith("Ultrasonic 0: [('u0', ")
    assert lines[-1] == "done"


def test_a_library_that_reads_the_clock_before_the_first_message(
    tmp_path: Path, capfd: pytest.CaptureFixture[str]
) -> None:
    # pygame.font.SysFont runs fc-list and reads the clock many times meanwhile: those reads
    # are the library's, so they never move the clock and the first message is at step 0.
    events, _trace, printed = five_runs(tmp_path, str(SHAPES / "font_first.py"), V11, capfd)
    first = next(json.loads(line) for line in events.splitlines() if '"command"' in line)
    assert (first["step"], first["message"]) == (0, "u0,u1")
    assert '"peek"' not in events  # a library's reads are not recorded
    # subprocess's wait for fc-list sleeps on the wall clock: only the program's sleeps count
    sleeps = [json.loads(e)["value"] for e in events.splitlines() if '"sleep"' in e]
    assert sleeps == [0.05, 0.05, 1.0] * 2
    assert printed.splitlines()[-1] == "done"


def test_select_with_a_timeout(tmp_path: Path, capfd: pytest.CaptureFixture[str]) -> None:
    # A reply is ready for the first select after its message (no timeout spent waiting for
    # it); a select with nothing to come is a tenth of a simulated second.
    events, _trace, printed = five_runs(tmp_path, str(SHAPES / "select_timeout.py"), {}, capfd)
    lines = printed.splitlines()
    assert lines[0].startswith("Readings:")
    assert lines[0].endswith("] 0")  # no select timed out before the reply was there
    assert lines[-1] == "done"
    ticks = sum(int(line.split()[2]) for line in lines if line.startswith("Stopped after"))
    sleeps = [json.loads(e)["value"] for e in events.splitlines() if '"sleep"' in e]
    assert sleeps == [0.1] * ticks  # each select that timed out: 0.1 simulated seconds


@pytest.mark.parametrize("kind", ["poll", "epoll"])
def test_a_poll_object_with_a_timeout(
    kind: str, tmp_path: Path, capfd: pytest.CaptureFixture[str]
) -> None:
    # select.poll and select.epoll objects wait as select.select does: the reply is ready for
    # the first poll after its message; a poll with nothing to come is 0.1 simulated seconds.
    program = f"{SHAPES / 'poll_timeout.py'} {kind}"
    events, _trace, printed = five_runs(tmp_path, program, {}, capfd)
    lines = printed.splitlines()
    assert lines[0].startswith("Readings:")
    assert lines[0].endswith("] 0")  # no poll timed out before the reply was there
    assert lines[-1] == "done"
    ticks = sum(int(line.split()[2]) for line in lines if line.startswith("Stopped after"))
    assert ticks > 3  # the drives took several tenths of a second each
    sleeps = [json.loads(e)["value"] for e in events.splitlines() if '"sleep"' in e]
    assert sleeps == [0.1] * ticks  # each poll that timed out: 0.1 simulated seconds


def test_a_socket_timeout(tmp_path: Path, capfd: pytest.CaptureFixture[str]) -> None:
    # recv with a timeout: the reply first, then a timeout of 0.2 simulated seconds.
    events, _trace, printed = five_runs(tmp_path, str(SHAPES / "socket_timeout.py"), {}, capfd)
    sleeps = [json.loads(e)["value"] for e in events.splitlines() if '"sleep"' in e]
    assert sleeps
    assert set(sleeps) == {0.2}
    assert printed.splitlines()[-1] == "done"


def test_an_asyncio_client(tmp_path: Path, capfd: pytest.CaptureFixture[str]) -> None:
    # asyncio.sleep and wait_for go through the selectors: simulated time.
    _events, _trace, printed = five_runs(tmp_path, str(SHAPES / "asyncio_client.py"), {}, capfd)
    lines = printed.splitlines()
    assert lines[0].startswith("Readings: [")
    assert lines[-1] == "done"
