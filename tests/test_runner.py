"""The simulation loop: it alone touches the simulation, serves the bus, steps, pauses."""

from __future__ import annotations

import math
import threading

import pytest

from link_support import serving
from simmer.errors import BusClosed, WrongThread
from simmer.protocol import Decoded
from simmer.runner import Runner
from simmer.transport import CommandBus
from simmer.world import Simulation
from simmer.world.events import CommandEvent, Event


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
    future = runner.bus.submit(Decoded(None, 3, "not utf-8"), "c")
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
    assert runner.sim.frame == 1


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
