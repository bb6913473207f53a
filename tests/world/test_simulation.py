"""Whole-simulation behaviour: the lab's dead reckoning, noise, determinism, reset, events."""

from __future__ import annotations

import logging
import math
import pickle
import subprocess
import sys
from typing import Any

import pytest

from simmer import Simulation
from simmer.world.events import (
    BlockedMoveEvent,
    CollisionEndEvent,
    CollisionEvent,
    CommandEvent,
    Event,
    ResetEvent,
    StepEvent,
)
from simmer.world.outcome import Outcome

from helpers import EXAMPLES, LAB_SEQUENCE, default_data, make_sim, run_sequence

TARGET = (66.0, 12.0)


def miss(sim: Simulation) -> float:
    return math.dist((sim.robot.pose.x, sim.robot.pose.y), TARGET)


@pytest.mark.parametrize("config", [None, EXAMPLES / "simmer_default.toml"])
def test_lab_dead_reckoning_reaches_the_block_without_noise(config: Any) -> None:
    sim = Simulation.from_config(config)
    run_sequence(sim, LAB_SEQUENCE)
    assert miss(sim) < 0.5


def test_lab_dead_reckoning_misses_with_lab_drive_bias() -> None:
    data = default_data()
    data["drives"]["w0"]["bias"] = {"x": 0, "y": 0, "rotation": 0.2}
    data["drives"]["r0"]["bias"] = {"x": 0, "y": 0, "rotation": 0.01}
    sim = make_sim(data)
    for message in LAB_SEQUENCE:
        sim.command(message)
        sim.run_until_idle(max_seconds=60)
    assert miss(sim) > 3.0


def noisy_data() -> dict[str, Any]:
    """The lab rover with every noise source on, plus a gyroscope, compass and infrared."""
    data = default_data()
    data["drives"]["w0"] |= {
        "bias": {"rotation": 0.2},
        "error": {"x": 0.02, "y": 0.05, "rotation": 1},
    }
    data["drives"]["r0"] |= {
        "bias": {"rotation": 0.01},
        "error": {"x": 0.003, "y": 0.003, "rotation": 0.02},
    }
    for sensor in ("u0", "u1", "u2", "u3"):
        data["sensors"][sensor]["error"] = 0.02
    data["sensors"] |= {
        "g0": {"type": "gyroscope"},
        "c0": {"type": "compass", "error": 0.01},
        "i0": {"type": "infrared", "position": [0, 1]},
    }
    data["rand_bias"] = True
    return data


def trace(sim: Simulation, steps: int = 1000) -> list[tuple[float, ...]]:
    """Every step: pose and every sensor; a drive command whenever the drives are idle."""
    rows = []
    moves = ["w0-8", "r0-45", "w0--4", "r0--60"]
    for i in range(steps):
        if not sim.robot.any_drive_moving:
            sim.command(moves[i % len(moves)])
        sim.step()
        rows.append((*sim.robot.pose, *sim.command("u0,u1,u2,u3,g0,c0,i0,m0,m1")))
    return rows


@pytest.mark.slow
def test_same_seed_gives_identical_traces_with_all_noise_on() -> None:
    assert trace(make_sim(noisy_data(), seed=42)) == trace(make_sim(noisy_data(), seed=42))


@pytest.mark.slow
def test_different_seeds_give_different_traces() -> None:
    assert trace(make_sim(noisy_data(), seed=1)) != trace(make_sim(noisy_data(), seed=2))


def test_without_rand_error_the_seed_comes_from_the_configuration() -> None:
    data = noisy_data() | {"seed": 7}
    assert make_sim(data).seed == 7
    assert trace(make_sim(data), 200) == trace(make_sim(data), 200)
    assert make_sim(default_data()).seed == 5489  # floor_seed when no seed is given


def test_rand_error_draws_fresh_entropy() -> None:
    data = noisy_data() | {"rand_error": True}
    first, second = make_sim(data), make_sim(data)
    assert first.seed != second.seed
    assert trace(first, 200) != trace(second, 200)
    # The seed a random run used reproduces it exactly.
    assert trace(make_sim(data, seed=first.seed), 200) == trace(
        make_sim(data, seed=first.seed), 200
    )


def test_reset_restores_start_including_random_state() -> None:
    sim = make_sim(noisy_data(), seed=5)
    first = trace(sim, 300)
    sim.command("xx")
    sim.reset()
    assert sim.time == 0.0
    assert sim.robot.pose == sim.robot.start_pose
    assert sim.command("m0") == [0.0]
    sim.reset()
    assert trace(sim, 300) == first


def test_observers_see_commands_steps_collisions_and_resets() -> None:
    sim = make_sim()
    events: list[Event] = []
    sim.add_observer(events.append)
    sim.command("w0-60")
    sim.run_until_idle()
    sim.reset()
    kinds = {type(e) for e in events}
    assert kinds == {
        CommandEvent, StepEvent, CollisionEvent, CollisionEndEvent, BlockedMoveEvent, ResetEvent
    }  # fmt: skip
    command = next(e for e in events if isinstance(e, CommandEvent))
    assert (command.message, command.replies) == ("w0-60", (math.inf,))
    assert sum(isinstance(e, CollisionEvent) for e in events) == 1


def test_manual_keys_move_without_odometers_and_pause_drives() -> None:
    sim = make_sim()
    sim.command("w0-12")
    sim.set_manual_keys("q")  # sideways toward robot +x, which is world -x at heading 180
    sim.step(30)
    assert sim.robot.pose.y == 42.0
    assert sim.robot.drives["w0"].remaining == 12.0
    sim.set_manual_keys(set())
    assert sim.command("m0") == [0.0]
    sim.run_until_idle()
    assert sim.robot.pose.y == pytest.approx(30.0, abs=1e-9)
    with pytest.raises(ValueError, match="manual keys"):
        sim.set_manual_keys("z")


def test_place_robot_refuses_walls() -> None:
    sim = make_sim()
    assert not sim.place_robot(12.0, 30.0, 0.0)  # inside the solid cell at row 2, column 1
    assert not sim.place_robot(-20.0, 30.0, 0.0)  # outside the maze
    assert sim.robot.pose == sim.robot.start_pose
    assert sim.place_robot(30.0, 42.0, 90.0)


def test_configuration_and_simulation_pickle_for_parallel_runs() -> None:
    sim = Simulation.from_config(EXAMPLES / "simmer_default.toml")
    assert pickle.loads(pickle.dumps(sim.config)) == sim.config
    sim.command("w0-5")
    sim.step(10)
    copy = pickle.loads(pickle.dumps(sim))
    sim.run_until_idle()
    copy.run_until_idle()
    assert copy.robot.pose == sim.robot.pose
    assert copy.command("u0,u1,c0,i0,g0") == sim.command("u0,u1,c0,i0,g0")


@pytest.mark.slow
def test_the_simulation_core_never_imports_pygame() -> None:
    code = (
        "import sys, simmer, simmer.client, simmer.runner, simmer.transport, simmer.serve\n"
        "sim = simmer.Simulation.from_config()\n"
        "sim.command('w0-1,u0'); sim.run_until_idle()\n"
        "print(sorted(m for m in sys.modules if m.startswith(('pygame', 'simmer.ui'))))\n"
    )
    done = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, check=True, timeout=120
    )
    assert done.stdout.strip() == "[]"


def test_a_blocked_move_says_which_command_when_and_how_far_it_got(
    caplog: pytest.LogCaptureFixture,
) -> None:
    sim = make_sim()
    outcome = Outcome.attach(sim)
    blocked: list[BlockedMoveEvent] = []
    sim.add_observer(lambda e: blocked.append(e) if isinstance(e, BlockedMoveEvent) else None)
    assert sim.command("w0-6") == [math.inf]
    sim.run_until_idle()
    assert blocked == []  # a free move is no blocked move
    started, y_before = sim.time, sim.robot.pose.y
    with caplog.at_level(logging.INFO, logger="simmer"):
        assert sim.command("w0-60") == [math.inf]  # the reply stays the original's
        sim.run_until_idle()
    (event,) = blocked
    assert (event.command, event.started, event.unit, event.amount) == ("w0-60", started, "in", 60)
    assert event.blocked_steps == sim.blocked_steps > 0
    assert 0 < event.done < 60
    assert abs(event.done - (y_before - sim.robot.pose.y)) < 1e-6  # the inches it really went
    assert event.time == sim.time  # said when the command's time was up
    said = f"blocked move: 'w0-60' at {started:.2f} s was blocked for {event.blocked_steps} steps"
    assert said in caplog.text
    report = outcome.report()
    assert report.blocked_moves == sim.blocked_moves == 1
    assert report.first_blocked_move == event.describe()
    assert f"blocked moves 1: first {event.describe()}" in report.summary()


def test_a_turn_stopped_by_xx_against_a_wall_is_a_blocked_move_too() -> None:
    data = default_data()
    data["robot_start_position"] = [3.5, 42.0]  # turned, the rover's 4 in ends reach the wall
    sim = make_sim(data)
    sim.command("r0-90")
    sim.step(10)
    sim.command("xx")
    assert sim.blocked_moves == 1
    assert sim.last_blocked is not None
    assert sim.last_blocked.unit == "deg"
    blocked = sim.last_blocked.blocked_steps
    assert 0 < blocked < 10
    assert sim.last_blocked.done == pytest.approx(2.0 * (10 - blocked))  # 2 deg a free step
    assert "(9%)" in sim.last_blocked.describe()
