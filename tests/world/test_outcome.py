"""The run's outcome, worked out from the simulation's events: Task 2 time, collisions, path,
commands and NaN replies, reset, placing the robot by hand, plain data; the project's
milestones and score."""

from __future__ import annotations

import dataclasses
import json
import logging
import math

import pytest

from simmer import Simulation
from simmer.world.events import Event, ReachedEvent
from simmer.world.outcome import Outcome, OutcomeReport

from helpers import (
    EXAMPLES,
    LAB_SEQUENCE,
    make_config,
    make_sim,
    project_data,
    project_sim,
    run_sequence,
)

SPEED = 6.0
"""in/s of the default rover's drive w0."""
TURN = 120.0
"""deg/s of its turning drive r0."""


def test_task2_time_of_the_lab_sequence() -> None:
    sim = make_sim()
    outcome = Outcome.attach(sim)
    events: list[Event] = []
    sim.add_observer(events.append)
    dt = sim.dt
    run_sequence(sim, LAB_SEQUENCE[:-1])  # everything but the final spin
    # 36 + 36 + 12 + 24 + 6 in at 6 in/s and four quarter turns at 120 deg/s: 22 s.
    driving = (36 + 36 + 12 + 24 + 6) / SPEED + 4 * 90 / TURN
    assert sim.time == pytest.approx(driving)
    report = outcome.report()
    assert report.first_motion == 0.0  # the first command was sent at t = 0
    # At (66, 12), heading 180: the nose is 1.5 in short of the block's near side (y 6.5).
    assert not report.reached
    assert report.task2_time is None

    run_sequence(sim, LAB_SEQUENCE[-1:])  # r0-720: spins in place, 2 deg a step
    # The spin swings the back corner (robot frame (2.875, -4), radius R) toward the block's
    # near corner (64.5, 6.5), at B from the robot's centre: they are 1 in apart when the angle
    # between them is phi (law of cosines). World y points down the screen, where a clockwise
    # turn adds to the angles.
    corner = math.atan2(4.0, -2.875)  # at heading 180 the corner is at world (-2.875, +4)
    block_corner = math.atan2(6.5 - 12.0, 64.5 - 66.0) + 2 * math.pi
    r, b = math.hypot(2.875, 4.0), math.hypot(1.5, 5.5)
    phi = math.acos((r * r + b * b - 1.0) / (2 * r * b))
    turned = math.degrees(block_corner - corner - phi)
    assert turned == pytest.approx(122.2, abs=0.1)
    steps = math.ceil(turned / (TURN * dt))  # the first step that ends within 1 in
    expected = driving + steps * dt
    report = outcome.report()
    assert report.reached
    assert report.reached_at == pytest.approx(expected, abs=1e-9)
    assert report.task2_time == pytest.approx(expected, abs=1e-9)
    step = round(expected / dt)  # the steps done when it was reached
    reached = [event for event in events if isinstance(event, ReachedEvent)]
    assert [(e.time, e.task2_time, e.step) for e in reached] == [
        (report.reached_at, report.task2_time, step)
    ]  # told to the other observers, once
    assert report.path_length == pytest.approx(36 + 36 + 12 + 24 + 6)
    assert (report.messages, report.commands, report.nan_replies) == (10, 10, 0)
    assert report.collisions == 0
    assert report.final_pose == sim.robot.pose
    assert f"Task 2 time {expected:.2f} s" in report.summary()


def test_first_motion_is_the_start_of_the_first_step_that_moves() -> None:
    sim = make_sim()
    outcome = Outcome.attach(sim)
    sim.step(30)
    sim.command("u0")
    sim.step(30)
    assert outcome.report().first_motion is None  # reading a sensor is no motion
    sim.command("w0-1")  # sent at t = 1 s; the next step moves
    sim.step()
    assert outcome.report().first_motion == pytest.approx(1.0)
    assert outcome.task2_time() == pytest.approx(sim.dt)  # the stopwatch runs ...
    assert outcome.report().task2_time is None  # ... but the block is not reached


def test_reaching_means_within_one_inch_and_freezes_the_time(
    caplog: pytest.LogCaptureFixture,
) -> None:
    sim = make_sim()
    outcome = Outcome.attach(sim)
    block = sim.block
    # Facing the block from below, 1.2 in short of it (heading 180: up; the nose is 4 in ahead).
    assert sim.place_robot(block.x, block.y + block.size / 2 + 1.2 + 4, 180)
    sim.step(30)
    assert not outcome.report().reached  # not moved yet
    with caplog.at_level(logging.INFO, logger="simmer.outcome"):
        sim.command("w0-0.5")  # 0.1 in a step: two steps close 0.2 in; stops 0.7 in short
        sim.run_until_idle()
    report = outcome.report()
    assert report.first_motion == pytest.approx(0.5)
    assert report.task2_time == pytest.approx(2 * sim.dt)
    assert report.path_length == pytest.approx(0.5)  # the placement is no motion
    assert "reached the block at 0.53 s (Task 2 time 0.03 s)" in caplog.text
    sim.step(10)
    assert outcome.report().task2_time == report.task2_time  # frozen once reached


def test_each_collision_is_counted_once_with_the_first_ones_time() -> None:
    sim = make_sim()
    outcome = Outcome.attach(sim)
    dt = sim.dt
    sim.command("w0-50")  # the nose is 38 in below the top wall: the last 12 in are blocked
    sim.run_until_idle()
    report = outcome.report()
    assert report.collisions == 1
    assert report.blocked_steps > 100  # many steps blocked, one collision
    # 0.1 in a step: the step that would touch the wall is the 380th, which starts at 379 dt.
    assert report.first_collision == pytest.approx(38 / SPEED - dt)
    sim.command("w0--6")
    sim.run_until_idle()
    sim.command("w0-12")  # into the same wall again
    sim.run_until_idle()
    report = outcome.report()
    assert report.collisions == 2
    assert report.first_collision == pytest.approx(38 / SPEED - dt)
    assert report.collisions == sim.collisions


def test_path_length_of_a_twelve_inch_move_is_twelve() -> None:
    sim = make_sim()
    outcome = Outcome.attach(sim)
    run_sequence(sim, ["w0-12"])
    assert outcome.report().path_length == pytest.approx(12.0)
    run_sequence(sim, ["w0--3"])  # backwards counts too
    assert outcome.report().path_length == pytest.approx(15.0)
    run_sequence(sim, ["r0-90"])  # turning in place adds none
    assert outcome.report().path_length == pytest.approx(15.0)


def test_commands_and_busy_and_nan_replies_are_counted_apart() -> None:
    sim = make_sim()
    outcome = Outcome.attach(sim)
    assert math.isnan(sim.command("u0,zz")[1])  # no device zz
    assert sim.command("w0-3") == [math.inf]
    assert math.isnan(sim.command("w0-3")[0])  # the drive is busy
    assert math.isnan(sim.command("w0-0")[0])  # "is it idle?": not yet
    assert sim.command("w0-abc,r0-90,u0")[:2] != [math.inf] * 2  # malformed; busy
    report = outcome.report()
    assert (report.messages, report.commands) == (5, 8)
    assert (report.busy_replies, report.nan_replies) == (3, 2)
    assert "3 busy (a drive still moving), 2 NaN replies" in report.summary()
    sim.run_until_idle()
    assert math.isnan(sim.command("w0-abc")[0])  # malformed, nothing moving: NaN
    assert (outcome.report().busy_replies, outcome.report().nan_replies) == (3, 3)


def test_reset_clears_everything() -> None:
    sim = make_sim()
    outcome = Outcome.attach(sim)
    sim.command("zz")
    sim.command("w0-50")
    sim.run_until_idle()
    before = outcome.report()
    assert before.collisions == 1
    assert before.path_length > 0
    assert before.nan_replies == 1
    sim.reset()
    assert outcome.report() == Outcome(make_sim()).report()  # as at the start of a fresh run
    sim.step(10)
    sim.command("w0-1")
    sim.run_until_idle()
    report = outcome.report()
    assert report.first_motion == pytest.approx(10 * sim.dt)  # the stopwatch starts again
    assert report.path_length == pytest.approx(1.0)
    assert (report.collisions, report.blocked_steps) == (0, 0)


def test_placing_the_robot_restarts_the_stopwatch_but_not_the_run() -> None:
    sim = make_sim()
    outcome = Outcome.attach(sim)
    sim.command("zz")
    run_sequence(sim, ["w0-6"])
    assert outcome.report().first_motion == 0.0
    assert sim.place_robot(*sim.robot.pose)  # put back where it was: nothing changes
    assert outcome.report().first_motion == 0.0
    assert sim.place_robot(18, 42, 90)
    sim.step(10)
    report = outcome.report()
    assert report.first_motion is None
    assert report.path_length == pytest.approx(6.0)  # the hand's move is not the robot's path
    assert (report.messages, report.nan_replies) == (2, 1)  # the run's figures stand
    time = sim.time
    run_sequence(sim, ["w0-2"])
    report = outcome.report()
    assert report.first_motion == pytest.approx(time)
    assert report.path_length == pytest.approx(8.0)


def test_report_is_plain_json_data() -> None:
    sim = make_sim()
    outcome = Outcome.attach(sim)
    sim.command("zz")
    run_sequence(sim, LAB_SEQUENCE)
    report = outcome.report()
    data = report.as_dict()
    fields = {field.name for field in dataclasses.fields(OutcomeReport)}
    # a Lab 1 run has no project figures, a program that reports no pose no localization, a
    # run without the link model no link figures
    assert set(data) == fields - {"project", "localization", "link"}
    assert json.loads(json.dumps(data, allow_nan=False)) == data
    assert data["final_pose"] == list(sim.robot.pose)
    assert data["reached"] is True
    assert data["task2_time"] == report.task2_time
    assert data["nan_replies"] == 1
    assert data["first_collision"] is None


DELIVER_TO_B3 = ["w0-25", "g0-1", "w0--25", "r0-90", "w0-24", "r0--90", "w0-6", "g0-0"]
"""From the lab's start: up into the loading zone around a block at [6, 14], back to the
bottom row, right two cells, up into B3 (cell [2, 2]) and let go."""


@pytest.mark.parametrize(("target", "score"), [("B3", 100.0), ("B1", 50.0)])
def test_milestones_and_score_of_a_delivery(target: str, score: float) -> None:
    sim = project_sim(block="6,14", target=target)
    outcome = Outcome.attach(sim)
    times = []
    for message in DELIVER_TO_B3:
        sim.command(message)
        sim.run_until_idle()
        times.append(sim.time)
    project = outcome.report().project
    assert project is not None
    assert project.target == target
    assert sim.collisions == 0
    assert sim.zones.dropoff_at(sim.block.x, sim.block.y) == "B3"
    assert project.entered_loading
    assert project.picked_up
    assert project.left_loading
    assert project.entered_loading_at is not None
    assert project.entered_loading_at < times[0]
    assert project.picked_up_at == times[0]  # the command at the end of the first move
    assert project.left_loading_at is not None
    assert times[1] < project.left_loading_at < times[2]
    assert project.delivered is (target == "B3")
    assert project.delivered_at == (times[-1] if target == "B3" else None)
    assert project.wrong_zone == (None if target == "B3" else "B3")
    assert project.score == score
    line = outcome.report().summary()
    assert f"project (target {target})" in line
    assert f"score {score:g}" in line
    flat = outcome.report().as_dict()
    assert flat["delivered"] is (target == "B3")
    assert flat["score"] == score


def test_collisions_and_the_time_limit_cost_points() -> None:
    data = project_data(block="6,14", target="B3")
    data["score"] = {"collision": -5, "time_limit": 10}
    sim = Simulation(make_config(data), seed=1)
    outcome = Outcome.attach(sim)
    sim.command("w0--10")  # backwards into the bottom wall
    sim.run_until_idle()
    assert sim.place_robot(6.0, 42.0, 180.0)  # back to the start, by hand
    for message in DELIVER_TO_B3:
        sim.command(message)
        sim.run_until_idle()
    project = outcome.report().project
    assert project is not None
    assert project.delivered
    assert project.left_loading_at is not None
    assert project.left_loading_at < 10
    assert project.delivered_at is not None
    assert project.delivered_at > 10
    assert project.score == 10 + 20 + 10 - 5  # the delivery came too late; one collision


def test_a_lab1_run_has_no_project_in_its_outcome() -> None:
    sim = Simulation.from_config(EXAMPLES / "lab1_rover.toml")
    outcome = Outcome.attach(sim)
    sim.step()
    report = outcome.report()
    assert report.project is None
    assert "project" not in report.summary()
    assert "score" not in report.as_dict()
