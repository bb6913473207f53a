"""The two clocks behind one interface: what a message and a clock message cost in real time
and in lockstep, and that the bytes a transport sets aside reach the clock it was given."""

from __future__ import annotations

import logging

import pytest

from link_support import read_frame, serving, stream
from simmer.clock import Clock, LockstepClock, RealTimeClock, make_clock
from simmer.lockstep import FREE_TIME_READS
from simmer.protocol import ClockText, parse_clock
from simmer.runner import Runner
from simmer.transport.bus import Request
from simmer.world import Simulation

from helpers import wait_for


def _ask(clock: Clock, text: str) -> Request:
    """Hand ``clock`` the clock message ``text``; the request its answer goes into."""
    request = Request(ClockText(text), "test")
    clock.start(request, parse_clock(text))
    return request


def test_make_clock_picks_the_kind_and_a_runner_only_talks_to_it() -> None:
    sim = Simulation.from_config()
    assert isinstance(make_clock(sim), RealTimeClock)
    lockstep = make_clock(sim, lockstep=True, link_delay=0.5)
    assert isinstance(lockstep, LockstepClock)
    assert lockstep.link_delay == 0.5
    assert Runner(sim, clock=lockstep).clock is lockstep
    assert Runner(sim, lockstep=True).link_delay == sim.dt  # one step by default


def test_a_lockstep_link_delay_must_be_a_time() -> None:
    with pytest.raises(ValueError, match="link_delay must be 0 or more seconds"):
        LockstepClock(Simulation.from_config(), -1.0)


def test_in_lockstep_a_message_costs_the_link_delay_and_a_sleep_its_seconds() -> None:
    sim = Simulation.from_config()
    clock = LockstepClock(sim, link_delay=0.25)
    clock.message(4)
    assert (clock.time, clock.taken) == (0.25, 4)
    assert clock.due()
    clock.catch_up()
    assert not clock.due()
    sleep = _ask(clock, "!sleep 1")
    assert not sleep.future.done()  # answered when the simulation is there
    clock.catch_up()
    assert sleep.future.result() == [1.25]
    assert sim.time == pytest.approx(1.25, abs=sim.dt)


def test_in_lockstep_only_a_long_run_of_clock_reads_advances_a_step() -> None:
    sim = Simulation.from_config()
    clock = LockstepClock(sim)
    for _ in range(FREE_TIME_READS):
        read = _ask(clock, "!time")
        clock.catch_up()
        assert read.future.result() == [0.0]
    read = _ask(clock, "!time")
    clock.catch_up()
    assert read.future.result() == [sim.dt]


def test_in_real_time_a_message_costs_nothing_and_a_sleep_waits_for_the_steps() -> None:
    sim = Simulation.from_config()
    clock = RealTimeClock(sim)
    clock.message(4)
    assert (clock.link_delay, clock.taken, sim.time) == (0.0, 4, 0.0)
    assert clock.due()
    assert not clock.holding()
    assert _ask(clock, "!time").future.result() == [0.0]
    sleep = _ask(clock, "!sleep 0.1")
    assert clock.waiting
    while not sleep.future.done():
        sim.step()
        clock.settle()
    assert sleep.future.result() == [pytest.approx(0.1, abs=sim.dt)]
    assert not clock.waiting


def test_a_question_line_is_counted_by_the_clock_the_transports_were_given(
    caplog: pytest.LogCaptureFixture,
) -> None:
    """``?`` is set aside by the stream transport, not answered by the loop: its two bytes
    reach the runner's clock, so a ``!sync @2`` sent on another connection is answered at
    once, not after the clock gave up waiting for them."""
    caplog.set_level(logging.WARNING, "simmer.runner")
    with serving(speed=None) as (runner, link):
        port = link.stream.port
        with stream(port) as asker, stream(port) as syncer:
            asker.sendall(b"?\n")
            wait_for(lambda: runner.clock.taken == 2, "the question line taken")
            syncer.sendall(b"!sync @2\n")
            (value,) = read_frame(syncer)
    assert value >= 0.0
    assert "never arrived" not in caplog.text
