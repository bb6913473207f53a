"""The link model in a served run (issue 33, item 1): a student's two-port program and a
pyserial program see its delays under ``--program``; a lossy link repeats with its seed; the
client library copes (timeouts, resynchronising); the events, the report and the HUD's
outcome count what the link did; in real time a reply waits for simulated time."""

from __future__ import annotations

import json
import math
import socket
import sys
import threading
from pathlib import Path
from typing import Any

import pytest

from link_support import read_frame, run_program
from simmer import Simulation
from simmer.options import RunOptions
from simmer.runner import Runner
from simmer.serve import make_link
from simmer.transport import Transports
from simmer.transport.link import LinkModel
from simmer.world.events import CommandEvent, Event, RunEvent

from helpers import default_data, make_config, wait_for

pytestmark = pytest.mark.timeout(240)

BYTE = 10 / 9600
"""Seconds a byte takes at 9600 baud (8N1: 10 bits)."""
# A program's time.time() is seconds since 1970 as a float: a microsecond is its resolution.

TWO_PORT = """\
import socket, time

def ask(message, wait):
    start = time.time()
    with socket.create_connection(("127.0.0.1", 61200)) as out:
        out.sendall(message)
    time.sleep(wait)
    with socket.create_connection(("127.0.0.1", 61201)) as back:
        data = back.recv(64)
    return data, time.time() - start

for message in (b"u0", b"u0,u1,u2"):
    data, took = ask(message, 0.05)
    print(message.decode(), len(data), repr(took))
"""
"""A student's two-port program: send, sleep a little, collect; it times each exchange."""

PYSERIAL = """\
import os, time
import serial

port = serial.Serial(os.environ["SIMMER_SERIAL"], 9600, timeout=1)
for message in (b"u0\\n", b"u0,u1,u2\\n"):
    start = time.time()
    port.write(message)
    data = port.read(4 * (message.count(b",") + 1))
    print(message.strip().decode(), len(data), repr(time.time() - start))
"""
"""A pyserial program as a team writes it against the robot's Bluetooth port."""

CLIENT = """\
import time
from simmer.client import connect
from simmer.errors import ReplyTimeout

robot = connect(timeout=0.5)
good = failed = 0
readings = []
for i in range(150):
    try:
        readings.append(round(robot.read("u0"), 3))
        good += 1
    except ReplyTimeout:
        failed += 1
print("good", good, "failed", failed, "clock", round(time.monotonic(), 4))
print("readings", readings[:40])
"""
"""A program on simmer.client reading a sensor over and over through a lossy link."""


SERIAL_CLIENT = """\
import math, os, time
from simmer.client import connect
from simmer.errors import ReplyTimeout

robot = connect(serial=os.environ["SIMMER_SERIAL"], timeout=0.5)
good = failed = 0
readings = []
for i in range(150):
    try:
        readings.append(robot.read("u0"))
        good += 1
    except ReplyTimeout:
        failed += 1
kept = [r for r in readings if not math.isnan(r)]
print("good", good, "failed", failed, "clock", round(time.monotonic(), 4))
print("nan", len(readings) - len(kept), "sum", round(sum(kept), 3))
"""
"""The same through the serial port (pyserial, packed replies): no frames to find again,
so after a reply that timed out the library empties the port's input before writing."""


def linked(**link: Any) -> Simulation:
    """The default robot with ``[link]`` set to ``link`` (seed 11)."""
    data = default_data()
    data["link"] = link
    return Simulation(make_config(data), seed=11)


def printed(sim: Simulation, tmp_path: Path, program: str, capfd: Any, **options: Any) -> str:
    """Run ``program`` under ``--program`` on the lockstep clock; what it printed."""
    script = tmp_path / "program.py"
    script.write_text(program, encoding="utf-8")
    served = run_program(sim, f"{sys.executable} {script}", **options)
    out = capfd.readouterr().out
    assert (served.ended_by, served.exit_status) == ("program", 0), out
    return out


def times(out: str) -> dict[str, tuple[int, float]]:
    """``message -> (reply bytes, seconds)`` from a program's lines."""
    rows = [line.split() for line in out.splitlines() if line[:1] == "u"]
    return {row[0]: (int(row[1]), float(row[2])) for row in rows}


@pytest.mark.slow
def test_a_two_port_student_program_sees_the_link_s_delays(
    tmp_path: Path, capfd: pytest.CaptureFixture[str]
) -> None:
    sim = linked(preset="custom", latency=0.012)
    seen = times(printed(sim, tmp_path, TWO_PORT, capfd))
    # the command reaches the robot during the program's 0.05 s sleep (12 ms and its bytes);
    # the reply is collected after it: the latency again and its bytes at 9600 baud
    assert seen["u0"] == (4, pytest.approx(0.05 + 0.012 + 4 * BYTE, abs=1e-6))
    assert seen["u0,u1,u2"] == (12, pytest.approx(0.05 + 0.012 + 12 * BYTE, abs=1e-6))
    slow = times(printed(linked(preset="custom", latency=0.06), tmp_path, TWO_PORT, capfd))
    # a command still on its way when the sleep ends (60 ms): the reply waits for it
    assert slow["u0"] == (4, pytest.approx(0.06 + 2 * BYTE + 0.06 + 4 * BYTE, abs=1e-6))
    off = times(
        printed(Simulation(make_config(default_data()), seed=11), tmp_path, TWO_PORT, capfd)
    )
    assert off["u0"][1] < 0.05 + 2 * 0.012  # without the model: the sleep and a step at most


@pytest.mark.slow
def test_a_pyserial_program_sees_the_link_s_delays(
    tmp_path: Path, capfd: pytest.CaptureFixture[str]
) -> None:
    pytest.importorskip("serial")
    sim = linked(preset="custom")
    seen = times(printed(sim, tmp_path, PYSERIAL, capfd, serial=True))
    # "u0\n" and a 4-byte float: 7 bytes at 9600 baud, 7.3 ms
    assert seen["u0"] == (4, pytest.approx(7 * BYTE, abs=1e-6))
    assert seen["u0,u1,u2"] == (12, pytest.approx((9 + 12) * BYTE, abs=1e-6))


def _run_lossy(seed: int, tmp_path: Path, capfd: Any) -> tuple[str, list[str]]:
    data = default_data()
    data["link"] = {"preset": "hc05-9600", "loss": 0.02, "corruption": 0.01, "dropout_every": 5}
    sim = Simulation(make_config(data), seed=seed)
    events: list[str] = []

    def keep(event: Event) -> None:
        if isinstance(event, CommandEvent):
            events.append(f"{event.time:.6f} {event.message!r} {event.replies}")
        elif isinstance(event, RunEvent) and event.what.startswith("link"):
            events.append(f"{event.time:.6f} {event.what} {event.value} {event.detail}")

    sim.add_observer(keep)
    return printed(sim, tmp_path, CLIENT, capfd), events


@pytest.mark.slow
def test_a_lossy_link_gives_the_same_run_with_the_same_seed_and_the_client_copes(
    tmp_path: Path, capfd: pytest.CaptureFixture[str]
) -> None:
    first, first_events = _run_lossy(11, tmp_path, capfd)
    again, again_events = _run_lossy(11, tmp_path, capfd)
    other, _ = _run_lossy(12, tmp_path, capfd)
    assert first == again
    assert first_events == again_events
    assert first != other
    # replies were lost or garbled, and the library raised ReplyTimeout for each and carried
    # on: every later reading is a whole reply of its own (none taken for another's)
    good, failed = (int(word) for word in first.split()[1:4:2])
    assert good + failed == 150
    assert 0 < failed < 75
    kinds = {line.split()[1] for line in first_events if " link-" in line}
    assert {"link-lost", "link-dropout"} <= kinds


@pytest.mark.slow
def test_a_lossy_serial_link_repeats_and_the_client_resynchronises(
    tmp_path: Path, capfd: pytest.CaptureFixture[str]
) -> None:
    pytest.importorskip("serial")

    def run() -> str:
        sim = linked(preset="hc05-9600", loss=0.02, corruption=0.01, dropout_every=5)
        return printed(sim, tmp_path, SERIAL_CLIENT, capfd, serial=True)

    first, again = run(), run()
    assert first == again
    good, failed = (int(word) for word in first.split()[1:4:2])
    assert good + failed == 150
    assert 0 < failed < 75
    # a late reply never shifts the rest: almost every reading is the wall 39.5 in away
    nan, total = first.split("\n")[1].split()[1:4:2]
    assert abs(float(total) / (good - int(nan)) - 39.5) < 1.0


DROPOUT = """\
import sys, time
from simmer.client import connect
from simmer.errors import ReplyTimeout

robot = connect(timeout=0.3)
for at in map(float, sys.argv[1:]):
    time.sleep(at - time.monotonic())
    try:
        print(at, "reply", robot.read("u0"))
    except ReplyTimeout:
        print(at, "timeout")
"""
"""Reads at the times given, printing whether each was answered."""


@pytest.mark.slow
def test_a_dropout_loses_what_is_sent_in_it_and_the_link_comes_back_after(
    tmp_path: Path, capfd: pytest.CaptureFixture[str]
) -> None:
    link = {"preset": "custom", "dropout_every": 5.0, "dropout_seconds": 2.0}
    sim = linked(**link)
    params = sim.config.settings.link.resolved()
    assert params is not None
    start, end = LinkModel(params, sim.stream).window  # the run's first dropout, from its seed
    assert end - start == 2.0
    assert start > 0.5  # seed 11's first dropout leaves time to read before it
    times = [start - 0.2, start + 0.1, start + 1.5, end + 0.1, end + 0.5]
    script = tmp_path / "dropout.py"
    script.write_text(DROPOUT, encoding="utf-8")
    served = run_program(sim, f"{sys.executable} {script} " + " ".join(map(repr, times)))
    out = capfd.readouterr().out
    assert served.exit_status == 0, out
    said = [line.split()[1] for line in out.splitlines()]
    assert said == ["reply", "timeout", "timeout", "reply", "reply"]
    assert served.outcome.report().link["dropouts"] == 1  # type: ignore[index]


@pytest.mark.slow
def test_the_report_and_the_outcome_count_what_the_link_did(
    tmp_path: Path, capfd: pytest.CaptureFixture[str]
) -> None:
    sim = linked(preset="hc05-9600", loss=0.02, corruption=0.01)
    folder = tmp_path / "run"
    printed(sim, tmp_path, CLIENT, capfd, record=folder)
    outcome = json.loads((folder / "report.json").read_text(encoding="utf-8"))["outcome"]
    # a message reaches the robot whole or not, its reply goes back: at most 150 of each
    assert 150 < outcome["link_messages"] <= 300
    assert outcome["link_bytes"] <= 150 * (3 + 7)
    assert outcome["link_lost"] > 0
    assert outcome["link_corrupted"] > 0
    assert outcome["link_seconds"] > 150 * 0.012
    report = (folder / "report.md").read_text(encoding="utf-8")
    row = "| The link: bytes lost, bytes corrupted, dropouts (messages lost in them) |"
    assert f"{row} {outcome['link_lost']}, {outcome['link_corrupted']}, " in report
    events = (folder / "events.jsonl").read_text(encoding="utf-8")
    assert '"link-lost"' in events


def test_in_real_time_a_reply_waits_for_its_arrival_in_simulated_time() -> None:
    sim = linked(preset="custom", latency=0.25)
    runner = Runner(sim, speed=4.0)  # a quarter second of simulated time: 63 ms of wall time
    link = make_link(sim, runner)
    assert link is not None
    stop = threading.Event()
    thread = threading.Thread(target=runner.run, kwargs={"stop_event": stop})
    transports = Transports(
        runner.bus, sim.config, RunOptions.free_ports(), clock=runner.clock, link_model=link
    )
    with transports:
        thread.start()
        try:
            with socket.create_connection(("127.0.0.1", transports.stream.port)) as sock:
                wait_for(lambda: sim.steps > 0, "the first step")
                sent = sim.time
                sock.sendall(b"u0\n")
                (reading,) = read_frame(sock)
                arrived = sim.time
        finally:
            stop.set()
            thread.join()
            runner.bus.close()
    assert not math.isnan(reading)
    # both latencies and 10 bytes at 9600 baud, less a step for when the send landed
    assert arrived - sent >= 2 * 0.25 + 10 * BYTE - sim.dt
    assert link.model.counts.messages == 2


def test_with_the_model_off_no_link_is_made_and_nothing_is_counted() -> None:
    sim = Simulation(make_config(default_data()), seed=11)
    runner = Runner(sim, speed=None)
    assert make_link(sim, runner) is None
    from simmer.world.outcome import Outcome

    report = Outcome.attach(sim).report()
    assert report.link is None
    assert not any(key.startswith("link_") for key in report.as_dict())
    assert report.link_text() is None
