"""The simulation loop: it alone touches the simulation, serves the bus, steps, pauses; a
request that fails fails alone, its NaN reasons travel with it, and a client's bad commands
take a bounded number of log lines."""

from __future__ import annotations

import logging
import math
import re
import threading
from pathlib import Path

import pytest

from link_support import closed_by_server, read_frame, serving, stream, two_port_send
from simmer.config import load_config
from simmer.errors import BusClosed, WrongThread
from simmer.protocol import MAX_COMMANDS, Refused
from simmer.runner import LOG_LINES_PER_SECOND, Runner, _LogBudget
from simmer.transport import CommandBus
from simmer.transport.bus import Reply, Request
from simmer.world import Simulation
from simmer.world.events import CommandEvent, Event

from helpers import SIMMER_PY, wait_for


@pytest.fixture
def runner() -> Runner:
    return Runner(Simulation.from_config(), speed=None)


def test_serve_answers_queued_messages_in_order(runner: Runner) -> None:
    seen: list[Event] = []
    runner.sim.add_observer(seen.append)
    first = runner.bus.submit("w0-6", "a")
    second = runner.bus.submit("w0-6", "b")
    assert runner.serve() == 2
    assert first.result() == [math.inf]
    assert second.result()[0] != second.result()[0]  # NaN: a drive is busy
    assert [e.client for e in seen if isinstance(e, CommandEvent)] == ["a", "b"]


def test_undecodable_message_gets_nan_per_command(runner: Runner) -> None:
    future = runner.bus.submit(Refused("not utf-8", 3), "c")
    runner.serve()
    assert all(math.isnan(v) for v in future.result())
    assert len(future.result()) == 3


def test_run_until_simulated_time_and_on_frame_can_quit(runner: Runner) -> None:
    runner.run(until=0.5)
    assert runner.sim.time == pytest.approx(0.5, abs=runner.sim.dt)
    calls: list[float] = []

    def on_frame(r: Runner) -> bool:
        calls.append(r.sim.time)
        return len(calls) < 3

    runner.run(on_frame=on_frame)
    assert len(calls) == 3


def test_paused_runner_serves_but_does_not_step() -> None:
    runner = Runner(Simulation.from_config(), speed=1.0)
    runner.paused = True
    stop = threading.Event()
    thread = threading.Thread(target=runner.run, kwargs={"stop_event": stop})
    thread.start()
    try:
        assert runner.bus.submit("u0", "t").result(timeout=5)[0] > 0
        assert runner.sim.time == 0.0
    finally:
        stop.set()
        thread.join()
    runner.step_once()
    assert runner.sim.steps == 1


def test_speed_is_validated_and_changeable(runner: Runner) -> None:
    runner.speed = 4.0
    assert runner.speed == 4.0
    runner.speed = None
    with pytest.raises(ValueError, match="positive"):
        runner.speed = 0.0


def test_closed_bus_fails_pending_and_new_messages() -> None:
    bus = CommandBus()
    pending = bus.submit("u0", "a")
    bus.close()
    with pytest.raises(BusClosed):
        pending.result(timeout=1)
    with pytest.raises(BusClosed):
        bus.submit("u0", "b").result(timeout=1)


def test_clients_are_listed() -> None:
    bus = CommandBus()
    bus.connect("stream 1", "stream")
    assert Runner(Simulation.from_config(), bus=bus).clients == ["stream 1"]
    bus.disconnect("stream 1")
    assert bus.clients == []


def test_only_the_loop_thread_may_drive_a_served_simulation() -> None:
    sim = Simulation.from_config()
    with serving(sim):
        for drive in (lambda: sim.command("u0"), sim.step, sim.reset, sim.run_until_idle):
            with pytest.raises(WrongThread, match="belongs to the thread running its loop"):
                drive()
    assert sim.command("u1") == [pytest.approx(3.5)]  # the loop has ended: anyone may again


CONTROL = "\x1b[2J\x1b[31m\u202eevil\x07"
"""Clear the screen, turn red, reverse the line, ring the bell."""


@pytest.mark.parametrize("config", [None, SIMMER_PY / "lab_rover_quiet.py"])
def test_client_text_is_escaped_in_the_log(
    config: Path | None, caplog: pytest.LogCaptureFixture
) -> None:
    sim = Simulation(load_config(config))
    messages = [CONTROL, f"w0{CONTROL}", f"{CONTROL[:2]}-1", f"{CONTROL[:2]}x1", f"u0-{CONTROL}"]
    with caplog.at_level(logging.DEBUG):
        for message in messages:
            sim.command(message)
        Runner(sim).handle(Request(Refused(f"not text: {CONTROL}"), "client"))
    logged = [record.getMessage() for record in caplog.records]
    assert len(logged) >= len(messages)
    for line in logged:
        assert line.isprintable(), line
    assert any("\\x1b[2J" in line for line in logged)


def test_an_exception_executing_a_message_fails_that_request_only(
    caplog: pytest.LogCaptureFixture,
) -> None:
    caplog.set_level(logging.ERROR)
    sim = Simulation.from_config()

    def observer(event: object) -> None:
        if getattr(event, "message", None) == "u2":
            raise RuntimeError("a faulty observer")

    sim.observers.append(observer)
    with serving(sim) as (runner, link):
        with stream(link.stream.port) as sock:
            sock.sendall(b"u2\n")
            assert closed_by_server(sock)
        assert two_port_send(link, b"u1") == [pytest.approx(3.5)]
        assert runner.bus.submit("u1", "test").result(timeout=10) == [pytest.approx(3.5)]
    assert "a faulty observer" in caplog.text


def test_a_message_of_many_bad_commands_writes_a_few_log_lines(
    caplog: pytest.LogCaptureFixture,
) -> None:
    caplog.set_level(logging.WARNING)
    with serving() as (_, link), stream(link.stream.port) as sock:
        sock.sendall(b",".join([b"zz"] * MAX_COMMANDS) + b"\n")
        assert len(read_frame(sock)) == MAX_COMMANDS
    bad = [r for r in caplog.records if "bad command" in r.getMessage()]
    assert len(bad) <= 4
    assert f"{MAX_COMMANDS - 3} more bad commands" in caplog.text


def test_a_client_flooding_bad_commands_gets_ten_log_lines_a_second_then_a_count(
    caplog: pytest.LogCaptureFixture,
) -> None:
    caplog.set_level(logging.WARNING, logger="simmer.runner")
    now = [0.0]  # the budget's clock: the flood takes no time, however slow the machine
    with serving(speed=None) as (runner, link), stream(link.stream.port) as sock:
        runner._log = _LogBudget(clock=lambda: now[0])
        for _ in range(400):
            sock.sendall(b"zz\n")
            assert math.isnan(read_frame(sock)[0])
        assert "more log lines" not in caplog.text  # said once the second is over
        now[0] = seconds = 1.0
        wait_for(lambda: "more log lines in one second, not written" in caplog.text, "a count")
    written = [r for r in caplog.records if "no device 'zz'" in r.getMessage()]
    held = sum(
        int(m[1])
        for r in caplog.records
        if (m := re.search(r"(\d+) more log lines in one second", r.getMessage()))
    )
    assert len(written) <= LOG_LINES_PER_SECOND * (math.ceil(seconds) + 1)
    assert len(written) == LOG_LINES_PER_SECOND  # all 400 came within one second
    assert len(written) + held == 400


def test_a_request_carries_its_reasons() -> None:
    bus = CommandBus()
    runner = Runner(Simulation.from_config(), bus=bus)
    request = bus.request("u0,zz", "test")
    runner.serve()
    assert isinstance(request.future, Reply)
    assert request.future.result()[0] > 0
    assert len(request.reasons) == 1
    assert "no device 'zz'" in request.reasons[0]
    bus.close()


@pytest.mark.parametrize("keep_time", [False, True])
def test_a_held_up_loop_drops_its_backlog_unless_it_keeps_time(
    monkeypatch: pytest.MonkeyPatch, keep_time: bool
) -> None:
    """The window's loop drops a backlog past MAX_LAG (no racing to catch up); the
    ground-truth robot's (keep_time) catches up, so its clock stays the wall clock."""
    import types

    import simmer.runner

    sim = Simulation(load_config(), seed=1)
    wall = [0.0]
    looks = [0]
    """Looks at the clock since the loop was held up (-1: not yet)."""
    looks[0] = -1

    def monotonic() -> float:
        """10 ms a look; at 0.5 s, the loop held up 1 s; then 200 quick looks (catching up
        costs only steps)."""
        if looks[0] < 0 and sim.time >= 0.5:
            looks[0] = 0
            wall[0] += 1.0
        quick = 0 <= looks[0] < 200
        looks[0] += looks[0] >= 0
        wall[0] += 0.001 if quick else 0.01
        return wall[0]

    monkeypatch.setattr(simmer.runner, "time", types.SimpleNamespace(monotonic=monotonic))
    Runner(sim, speed=1.0, keep_time=keep_time).run(until=2.0)
    behind = wall[0] - sim.time
    if keep_time:
        assert behind < 0.1
    else:
        assert 0.7 < behind < 1.1  # the second held up, less MAX_LAG, is lost
