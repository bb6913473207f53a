"""The lockstep clock (issue 10): the same configuration, seed and program give the same run
through every transport, at any speed, while the machine is busy."""

from __future__ import annotations

import hashlib
import math
import subprocess
import sys
import threading
from pathlib import Path
from typing import Any

import pytest

from link_support import run_program
from simmer import Simulation
from simmer.client import Client
from simmer.clock import LockstepClock
from simmer.lockstep import runs_python
from simmer.runner import LocalLink, Runner
from simmer.serve import Served
from simmer.world.events import CommandEvent, Event, StepEvent

from helpers import EXAMPLES, REPO, noisy_config

pytestmark = pytest.mark.timeout(180)

PROGRAM = REPO / "tests" / "fixtures" / "lockstep" / "program.py"
sys.path.insert(0, str(PROGRAM.parent))
from program import drive_around  # noqa: E402


def noisy_sim() -> Simulation:
    """The default rover with noisy drives and sensors, seeded."""
    return Simulation(noisy_config(), seed=17)


class Fingerprint:
    """A hash of every command, reply and pose, with the simulated time of each."""

    def __init__(self, sim: Simulation) -> None:
        self.digest = hashlib.sha256()
        self.steps = 0
        sim.add_observer(self)

    def __call__(self, event: Event) -> None:
        if isinstance(event, CommandEvent):
            self.digest.update(repr((event.time, event.message, event.replies)).encode())
        elif isinstance(event, StepEvent):
            self.steps += 1
            self.digest.update(repr((event.time, tuple(event.pose))).encode())

    def hexdigest(self) -> str:
        return self.digest.hexdigest()


def lockstep_run(sim: Simulation, program: str, speed: float | None, serial: bool) -> Served:
    """``simmer run --headless --program PROGRAM`` on free ports; the program must succeed."""
    served = run_program(sim, program, speed=speed, serial=serial)
    assert served.ended_by == "program"
    assert served.exit_status == 0
    return served


def served_run(transport: str, speed: float | None = None) -> str:
    """Run the program through ``transport`` under ``simmer run``'s lockstep clock."""
    sim = noisy_sim()
    fingerprint = Fingerprint(sim)
    program = f"{sys.executable} {PROGRAM} {transport}"
    lockstep_run(sim, program, speed, serial=transport == "serial")
    return fingerprint.hexdigest()


def local_run() -> str:
    """The same program in this process, through the Python API."""
    sim = noisy_sim()
    fingerprint = Fingerprint(sim)
    link = LocalLink(sim)
    robot = Client(link, lockstep=True)
    drive_around(robot, robot.sleep, lambda: link.clock("!time"))
    return fingerprint.hexdigest()


@pytest.mark.slow
def test_one_program_gives_one_run_through_every_transport(busy_cpu: None) -> None:
    runs = {
        transport: [served_run(transport) for _ in range(3)]
        for transport in ("stream", "two-port", "serial")
    }
    runs["python"] = [local_run() for _ in range(3)]
    hashes = {digest for digests in runs.values() for digest in digests}
    assert len(hashes) == 1, runs


@pytest.mark.slow
def test_speed_does_not_change_the_run() -> None:
    assert served_run("stream", speed=None) == served_run("stream", speed=50.0)


def test_sleep_advances_exactly_and_clock_reads_are_free() -> None:
    sim = Simulation.from_config()
    link = LocalLink(sim)
    assert link.clock("!sleep 0.1") == pytest.approx(0.1)
    assert sim.steps == 6
    assert [link.clock("!time") for _ in range(16)] == [pytest.approx(0.1)] * 16
    assert sim.steps == 6  # sixteen reads in a row cost nothing
    assert link.clock("!time") == pytest.approx(0.1 + sim.dt)  # the seventeenth moves on
    assert link.exchange("u0") == [39.5]
    assert sim.steps == 8  # a message costs one step (the link delay)
    assert link.clock("!sleep 0.01") > sim.time - 1e-9  # a fraction of a step accumulates
    assert math.isnan(link.exchange("!sleep -1")[0])


def test_idle_waits_for_the_drives() -> None:
    sim = Simulation.from_config()
    link = LocalLink(sim)
    assert link.exchange("w0-12") == [math.inf]
    finished = link.clock("!idle")
    assert not sim.robot.any_drive_moving
    assert finished == pytest.approx(2.0 + sim.dt, abs=2 * sim.dt)


@pytest.mark.slow
def test_dead_reckoning_under_the_lockstep_clock_is_the_same_at_every_speed() -> None:
    reports = []
    for speed in (None, 20.0, None):
        program = f"{sys.executable} {EXAMPLES / 'dead_reckoning.py'}"
        served = lockstep_run(Simulation.from_config(), program, speed, serial=False)
        reports.append(served.outcome.report())
    first = reports[0]
    assert first.reached
    assert first.task2_time == pytest.approx(23.05, rel=0.10)  # the real-time run's
    assert all(report == first for report in reports)


@pytest.mark.slow
def test_the_cli_says_how_a_program_run_ended(tmp_path: Path) -> None:
    script = tmp_path / "quits.py"
    script.write_text("import time\ntime.sleep(1.5)\nraise SystemExit(5)\n")
    command = [sys.executable, "-m", "simmer", "run", "--headless", "--program",
               f"{sys.executable} {script}"]  # fmt: skip
    result = subprocess.run(command, capture_output=True, text=True, timeout=60, check=False)
    assert result.returncode == 5, result.stdout + result.stderr
    assert "the program exited with status 5" in result.stdout
    limited = subprocess.run(
        [*command, "--seconds", "1"], capture_output=True, text=True, timeout=60, check=False
    )
    assert limited.returncode == 3, limited.stdout + limited.stderr
    hang = tmp_path / "hangs.py"
    hang.write_text("import threading\nthreading.Event().wait()\n")  # never sleeps: hangs
    timed = subprocess.run(
        [sys.executable, "-m", "simmer", "run", "--headless", "--timeout", "0.5", "--program",
         f"{sys.executable} {hang}"],
        capture_output=True, text=True, timeout=60, check=False,
    )  # fmt: skip
    assert timed.returncode == 124, timed.stdout + timed.stderr


@pytest.mark.parametrize(
    ("command", "python"),
    [
        ("python my_robot.py", True),
        (f"{sys.executable} -u my_robot.py", True),
        ("py -3 my_robot.py", True),
        ("./my_robot.py", True),
        ("/bin/sh -c 'exit 0'", False),
        ("./robot_controller", False),
    ],
)
def test_python_programs_are_recognised(command: str, python: bool) -> None:
    assert runs_python(command) is python


def test_a_program_that_is_not_python_is_told_so() -> None:
    said: list[str] = []
    served = run_program(
        Simulation.from_config(), "/bin/sh -c 'exit 0'", echo=said.append, timeout=60
    )
    assert served.exit_status == 0
    assert any("does not look like a Python program" in line for line in said), said


ASK_AND_EXIT = """\
import socket

robot = socket.create_connection(("127.0.0.1", 61202))
robot.sendall(b"u0\\n")
print(len(robot.recv(64)))
robot.close()
"""


def test_a_program_that_exits_after_its_reply_still_pays_its_link_delay(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """The step a message costs is owed once its reply goes out; a loop thread starved of CPU
    until the program had exited and stopped the run never took it, so a run's last poses
    depended on the machine's load. Here the loop is held back until the stop comes, as a
    starved one is (``due`` says no), and the run still ends one step on."""
    stops: list[threading.Event] = []
    run, due = Runner.run, LockstepClock.due

    def watched_run(
        self: Runner, *args: Any, stop_event: threading.Event | None = None, **kw: Any
    ) -> None:
        stops.append(stop_event)
        run(self, *args, stop_event=stop_event, **kw)

    monkeypatch.setattr(Runner, "run", watched_run)
    monkeypatch.setattr(LockstepClock, "due", lambda self: due(self) and stops[0].is_set())
    program = tmp_path / "ask_and_exit.py"
    program.write_text(ASK_AND_EXIT)
    sim = Simulation.from_config()
    lockstep_run(sim, f"{sys.executable} {program}", None, serial=False)
    assert sim.steps == 1
