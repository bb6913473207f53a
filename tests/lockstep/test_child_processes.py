"""A process the program starts is not on the simulated clock (issue 30, item 3): under
``simmer run --program`` a child (``multiprocessing`` with fork or spawn, ``subprocess`` of
Python) that connects to the simulator, writes on a connection it inherited, opens the serial
port or sleeps is refused with one line saying why, and the run is the same every time; a
child that does not talk to the simulator (a worker computing, a command) is fine."""

from __future__ import annotations

import dataclasses
import hashlib
from pathlib import Path

import pytest

from link_support import run_program
from simmer import Simulation
from simmer.record.eventlog import event_line
from simmer.world.events import CommandEvent, Event

from helpers import make_config, noisy_data

pytestmark = pytest.mark.timeout(300)

PROGRAM = """\
import multiprocessing
import os
import socket
import struct
import subprocess
import sys
import time

import serial


def ask(robot, message):
    robot.sendall(message + b"\\n")
    width, count = struct.unpack("<BH", robot.recv(3))
    data = b""
    while len(data) < width * count:
        data += robot.recv(width * count - len(data))
    return struct.unpack("<" + ("d" if width == 8 else "f") * count, data)


def drive():
    with socket.create_connection(("127.0.0.1", 61202)) as robot:
        print("child got", ask(robot, b"w0-3"), flush=True)


def drive_on(robot):
    robot.sendall(b"w0-3\\n")


def drive_serial(port):
    port.write(b"[w0-3]")


def open_serial():
    serial.Serial(os.environ["SIMMER_SERIAL"], 9600, timeout=1).write(b"[w0-3]")


def computes(results):
    results.put(sum(range(1000)))


if __name__ == "__main__":
    robot = socket.create_connection(("127.0.0.1", 61202))
    port = serial.Serial(os.environ["SIMMER_SERIAL"], 9600, timeout=1)
    print("parent", ask(robot, b"u0,u1"), flush=True)
    fork, spawn = multiprocessing.get_context("fork"), multiprocessing.get_context("spawn")
    for context, target, args in [
        (fork, drive, ()), (fork, drive_on, (robot,)), (fork, drive_serial, (port,)),
        (spawn, drive, ()), (spawn, open_serial, ()),
    ]:
        child = context.Process(target=target, args=args)
        child.start()
        child.join()
        print(context.get_start_method(), target.__name__, "exit code", child.exitcode, flush=True)
    results = spawn.Queue()
    worker = spawn.Process(target=computes, args=(results,))
    worker.start()
    print("a worker computed", results.get(), flush=True)
    worker.join()
    echo = subprocess.run(["echo", "hi"], capture_output=True, text=True)
    print("echo says", echo.stdout.strip())
    code = "import time; print('child clock read'); time.time(); time.sleep(1)"
    sleeper = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    print("a python child that sleeps:", sleeper.returncode, sleeper.stdout.strip())
    print(sleeper.stderr.strip().splitlines()[-1], flush=True)
    time.sleep(0.5)
    print("parent", ask(robot, b"w0-2"), ask(robot, b"u0,u1"), round(time.monotonic(), 3))
"""
"""A student's program whose children try every way to the simulator, and two that do not."""


def event_digest(sim: Simulation) -> list[str]:
    """Collects every event of a run as ``events.jsonl`` writes it (the client's port, which
    the operating system chooses, left out)."""
    lines: list[str] = []

    def seen(event: Event) -> None:
        if isinstance(event, CommandEvent):
            event = dataclasses.replace(event, client=event.client.split(" ")[0])
        lines.append(event_line(event))

    sim.add_observer(seen)
    return lines


def run_once(program: Path, capfd: pytest.CaptureFixture[str]) -> tuple[str, str, str, str]:
    """One run with the serial port: what the program printed, its errors, the messages the
    simulator took and a digest of every event."""
    sim = Simulation(make_config(noisy_data()), seed=7)
    events = event_digest(sim)
    taken: list[str] = []
    sim.add_observer(lambda e: taken.append(e.message) if isinstance(e, CommandEvent) else None)
    served = run_program(sim, f"python {program}", serial=True)
    printed = capfd.readouterr()
    assert (served.ended_by, served.exit_status) == ("program", 0), printed
    digest = hashlib.sha256("".join(events).encode()).hexdigest()
    return printed.out, printed.err, " ".join(taken), f"{len(events)} events {digest}"


@pytest.mark.slow
def test_children_that_talk_to_the_simulator_are_refused_the_same_every_time(
    tmp_path: Path, capfd: pytest.CaptureFixture[str], request: pytest.FixtureRequest
) -> None:
    program = tmp_path / "robot.py"
    program.write_text(PROGRAM, encoding="utf-8")
    runs = [run_once(program, capfd) for _ in range(3)]
    request.getfixturevalue("busy_cpu")  # a CPU kept busy for the last two
    runs += [run_once(program, capfd) for _ in range(2)]
    assert runs[1:] == runs[:-1]

    out, err, taken, _events = runs[0]
    assert taken == "u0,u1 w0-2 u0,u1"  # the parent's messages, and no child's
    lines = out.splitlines()
    assert lines[1:6] == [
        "fork drive exit code 1",
        "fork drive_on exit code 1",
        "fork drive_serial exit code 1",
        "spawn drive exit code 1",
        "spawn open_serial exit code 1",
    ]
    assert lines[6:9] == [
        "a worker computed 499500",
        "echo says hi",
        "a python child that sleeps: 1 child clock read",
    ]
    refusals = [line for line in err.splitlines() if line.startswith("RuntimeError: ")]
    refusals.append(lines[9])
    assert [line.split(" cannot ")[1].split(" under ")[0] for line in refusals] == [
        "connect to the simulator",
        "write to the simulator",
        "write to the simulator",
        "connect to the simulator",
        "open the simulator's serial port",
        "sleep or wait on the simulated clock",
    ]
    assert all(
        "only the program's own process is on the simulated clock" in line for line in refusals
    )
    assert lines[10].startswith("parent ")
    assert lines[10].endswith(" 0.55")  # a sleep of 0.5 s and three messages of a step
