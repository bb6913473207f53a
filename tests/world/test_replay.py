"""One stream of events (issue 10): a run's input events, fed to a fresh simulation with the
same configuration and seed, reproduce every reply and every pose bit for bit."""

from __future__ import annotations

import math

import pytest

from simmer import Simulation
from simmer.world.events import (
    CollisionEndEvent,
    CollisionEvent,
    CommandEvent,
    Event,
    KeysEvent,
    PlaceEvent,
    ResetEvent,
    RunEvent,
    StepEvent,
)
from simmer.world.replay import replay

from helpers import drive_noisily, make_config, noisy_config, noisy_data


def a_noisy_run(events: list[Event]) -> Simulation:
    """A noisy run of every kind of input (a reset included), its events kept in ``events``."""
    sim = Simulation(noisy_config(), seed=23)
    sim.add_observer(events.append)
    drive_noisily(sim)
    return sim


def test_input_events_reproduce_a_noisy_run_bit_for_bit() -> None:
    recorded: list[Event] = []
    original = a_noisy_run(recorded)
    kinds = {type(event) for event in recorded}
    assert {CommandEvent, KeysEvent, PlaceEvent, ResetEvent, CollisionEvent} <= kinds
    assert CollisionEndEvent in kinds
    replayed_events: list[Event] = []
    result = replay(original.config, original.seed, recorded, [replayed_events.append])
    assert result.differences == []
    assert replayed_events == recorded  # every reply and every pose, with its time and step
    assert result.sim.robot.pose == original.robot.pose


@pytest.mark.slow
def test_a_different_seed_is_reported_as_different_replies() -> None:
    recorded: list[Event] = []
    original = a_noisy_run(recorded)
    result = replay(original.config, original.seed + 1, recorded)
    assert result.differences
    assert "answered" in result.differences[0]


def test_events_carry_time_and_step_and_observers_can_leave() -> None:
    sim = Simulation.from_config()
    seen: list[Event] = []
    sim.add_observer(seen.append)
    sim.step(3)
    sim.command("u0", client="stream 127.0.0.1:1")
    command = seen[-1]
    assert isinstance(command, CommandEvent)
    assert (command.step, command.client) == (3, "stream 127.0.0.1:1")
    assert command.time == sim.time
    steps = [e.step for e in seen if isinstance(e, StepEvent)]
    assert steps == [1, 2, 3]
    sim.remove_observer(seen.append)
    sim.step()
    assert len(seen) == 4


def test_the_loop_reports_pause_speed_and_clock_messages() -> None:
    from simmer.runner import LocalLink

    sim = Simulation.from_config()
    link = LocalLink(sim)
    seen: list[Event] = []
    sim.add_observer(seen.append)
    link.clock("!sleep 0.5")
    link.runner.paused = True
    link.runner.paused = False
    link.runner.speed = 2.0
    runs = [(e.what, e.value) for e in seen if isinstance(e, RunEvent)]
    assert runs == [("clock", 0.5), ("pause", 0.0), ("resume", 0.0), ("speed", 2.0)]
    assert math.isclose(sim.time, 0.5)


def test_the_tof_imu_and_encoder_kinds_replay_bit_for_bit() -> None:
    data = noisy_data()
    data["sensors"] |= {
        "t0": {"type": "tof", "position": [0, 4]},
        "t1": {"type": "tof", "preset": "vl53l1x", "rotation": 90, "units": "mm"},
        "i0": {"type": "imu", "position": [1, 1], "gyro_bias": 0.2},
        "e0": {"type": "encoder", "wheel": "left", "slip": 0.05},
        "e1": {"type": "encoder", "wheel": "right", "slip": 0.05},
    }
    sim = Simulation(make_config(data), seed=31)
    recorded: list[Event] = []
    sim.add_observer(recorded.append)
    reads = "t0,t1,i0-0,i0-1,i0-2,e0,e1"
    for message in ("w0-10", "r0-45", "w0--4", "r0--90"):
        sim.command(message)
        while sim.robot.any_drive_moving:
            sim.step()
            if sim.steps % 5 == 0:
                sim.command(reads)
    sim.command("e0-1," + reads)
    sim.set_manual_keys("wd")
    sim.step(30)
    sim.set_manual_keys("")
    sim.reset()
    sim.command("w0-3")
    sim.step(40)
    sim.command(reads)
    replies = [e.replies for e in recorded if isinstance(e, CommandEvent)]
    assert len({len(r) for r in replies}) > 1
    assert any(v not in (0.0, math.inf) for r in replies for v in r)
    replayed: list[Event] = []
    result = replay(sim.config, sim.seed, recorded, [replayed.append])
    assert result.differences == []
    assert replayed == recorded
