"""The six device kinds with exact expectations (BEHAVIOUR §4-5)."""

from __future__ import annotations

import logging
import math
from typing import Any

import numpy as np
import pytest

from simmer.devices import Infrared

from helpers import default_data, make_sim

INF = math.inf
PER_DEGREE = 2 * math.pi * 3.125 / 360  # lab rover wheel travel per degree of r0


def with_sensor(sensor_id: str, **settings: Any) -> dict[str, Any]:
    data = default_data()
    data["sensors"][sensor_id] = settings
    return data


def test_noiseless_ultrasonic_reads_distance_to_wall() -> None:
    sim = make_sim()
    # u0 sits 2.5 in ahead of the robot at (6, 42), facing up at the top wall y = 0.
    assert sim.command("u0")[0] == pytest.approx(39.5, abs=1e-9)
    # u1 faces +x: the wall at x = 12 is 12 - 6 - 2.5 = 3.5 in away.
    assert sim.command("u1")[0] == pytest.approx(3.5, abs=1e-9)


def test_ultrasonic_clamps_to_its_range() -> None:
    data = default_data()
    data["sensors"]["u0"] |= {"max_range": 20.0, "min_range": 0.0}
    data["sensors"]["u1"] |= {"min_range": 5.0}
    sim = make_sim(data)
    assert sim.command("u0,u1") == [20.0, 5.0]


def test_drive_forward_is_exact() -> None:
    sim = make_sim()
    assert sim.command("w0-36") == [INF]
    assert sim.run_until_idle()
    pose = sim.robot.pose
    assert (pose.x, pose.y, pose.heading) == pytest.approx((6.0, 6.0, 180.0), abs=1e-9)
    assert sim.time == pytest.approx(6.0, abs=1e-9)


def test_drive_backward_and_rotation_are_exact() -> None:
    sim = make_sim()
    sim.command("r0-90")
    sim.run_until_idle()
    assert sim.robot.pose.heading == pytest.approx(270.0, abs=1e-9)
    sim.command("r0--90")
    sim.run_until_idle()
    sim.command("w0--0.5")
    sim.run_until_idle()
    assert (sim.robot.pose.y, sim.robot.pose.heading) == pytest.approx((42.5, 180.0), abs=1e-9)


def test_motor_odometers_for_lab_rover() -> None:
    sim = make_sim()
    sim.command("w0-10")
    sim.run_until_idle()
    assert sim.command("m0,m1") == pytest.approx([10.0, 10.0], abs=1e-9)
    sim.command("r0-90")
    sim.run_until_idle()
    m0, m1 = sim.command("m0,m1")
    assert m0 - 10.0 == pytest.approx(90 * PER_DEGREE, abs=1e-9)
    assert m1 - 10.0 == pytest.approx(-90 * PER_DEGREE, abs=1e-9)


def test_drive_advances_speed_over_frame_rate_each_step() -> None:
    sim = make_sim()
    sim.command("w0-1")
    sim.step()
    assert sim.robot.pose.y == pytest.approx(42.0 - 6.0 / 60.0, abs=1e-12)
    assert sim.robot.drives["w0"].remaining == pytest.approx(0.9, abs=1e-12)


def test_busy_drive_answers_nan_and_stop_clears_it() -> None:
    sim = make_sim()
    assert sim.command("w0-12") == [INF]
    replies = sim.command("w0-6,r0-90")
    assert all(math.isnan(r) for r in replies)
    sim.step(60)  # one second: 6 in
    assert sim.command("xx") == [INF]
    assert not sim.robot.any_drive_moving
    sim.step(60)
    assert sim.robot.pose.y == pytest.approx(36.0, abs=1e-9)
    assert sim.command("r0-90") == [INF]


def test_unknown_device_and_bad_values_answer_nan_with_a_log_line(
    caplog: pytest.LogCaptureFixture,
) -> None:
    sim = make_sim()
    with caplog.at_level(logging.WARNING, logger="simmer"):
        replies = sim.command("z9,w0-abc,w0-nan,w0-inf,w0-1e308,w06,,u0")
    assert all(math.isnan(r) for r in replies[:-1])
    assert replies[-1] == pytest.approx(39.5)
    assert sim.robot.pose.y == 42.0
    assert not sim.robot.any_drive_moving
    assert len(caplog.records) == 7
    assert "no device 'z9'" in caplog.text
    assert "'abc' is not a decimal number" in caplog.text


def test_collision_stops_robot_at_wall_while_odometers_count() -> None:
    sim = make_sim()
    sim.command("w0-60")
    assert sim.run_until_idle()
    # The rover's nose is 4 in ahead of its centre; the top wall is at y = 0.
    assert 4.0 <= sim.robot.pose.y < 4.0 + 0.1 + 1e-9
    assert sim.command("m0,m1") == pytest.approx([60.0, 60.0], abs=1e-9)
    assert sim.collisions == 1
    assert sim.blocked_steps > 0


def test_collision_with_block() -> None:
    sim = make_sim()
    assert sim.place_robot(66.0, 18.0, 180.0)
    sim.command("w0-12")
    sim.run_until_idle()
    # The block's lower face is at y = 6.5; the nose must stop just short of it.
    assert 10.5 <= sim.robot.pose.y < 10.5 + 0.1 + 1e-9
    assert sim.collisions == 1


def test_gyroscope_drift_is_bias_times_time() -> None:
    sim = make_sim(with_sensor("g0", type="gyroscope", bias=0.25, error=0.0))
    sim.step(600)
    assert sim.command("g0")[0] == pytest.approx(0.25 * 10.0, abs=1e-9)


def test_gyroscope_integrates_turns_and_wraps() -> None:
    sim = make_sim(with_sensor("g0", type="gyroscope", bias=0.0, error=0.0))
    sim.command("r0--30")
    sim.run_until_idle()
    assert sim.command("g0")[0] == pytest.approx(330.0, abs=1e-9)
    sim.command("r0-400")
    sim.run_until_idle()
    assert sim.command("g0")[0] == pytest.approx(10.0, abs=1e-9)


def test_gyroscope_sees_manual_rotation() -> None:
    sim = make_sim(with_sensor("g0", type="gyroscope", bias=0.0, error=0.0))
    sim.set_manual_keys("d")
    sim.step(30)  # half a second at 120 deg/s
    sim.set_manual_keys("")
    assert sim.command("g0,m0")[0] == pytest.approx(60.0, abs=1e-9)
    assert sim.command("m0") == [0.0]


def test_compass_reads_heading_with_bias_and_wraps() -> None:
    sim = make_sim(with_sensor("c0", type="compass", bias=5.0, error=0.0))
    assert sim.command("c0")[0] == pytest.approx(185.0, abs=1e-9)
    sim.command("r0-200")
    sim.run_until_idle()
    assert sim.command("c0")[0] == pytest.approx(25.0, abs=1e-9)


def test_compass_noise_has_the_documented_spread() -> None:
    sim = make_sim(with_sensor("c0", type="compass", bias=0.0, error=0.01), seed=3)
    readings = np.array([sim.command("c0")[0] for _ in range(4000)])
    assert readings.mean() == pytest.approx(180.0, abs=0.5)
    assert readings.std() == pytest.approx(2 * 0.01 * 360, rel=0.05)


def find_uniform_corner(white: np.ndarray, colour: bool, solid: np.ndarray) -> tuple[int, int]:
    """A tile corner (ix, iy) whose four surrounding tiles all have ``colour``, in open floor."""
    rows, cols = white.shape
    for iy in range(2, rows - 2):
        for ix in range(2, cols - 2):
            if (white[iy - 1 : iy + 1, ix - 1 : ix + 1] == colour).all() and not solid[
                iy * 3 // 12, ix * 3 // 12
            ]:
                return ix, iy
    raise AssertionError("no such corner")


@pytest.mark.parametrize("colour", [True, False])
def test_infrared_reads_floor_colour(colour: bool) -> None:
    data = default_data()
    data["sensors"]["i0"] = {"type": "infrared", "position": [0, 0], "error": 0.0}
    sim = make_sim(data)
    maze = sim.maze
    ix, iy = find_uniform_corner(maze.floor_white, colour, maze.solid)
    x, y = ix * maze.tile, iy * maze.tile
    for heading in (0.0, 45.0, 90.0):
        if sim.place_robot(x, y, heading):
            break
    else:
        pytest.skip("no room for the robot at that corner")
    sensor = sim.robot.sensors["i0"]
    assert isinstance(sensor, Infrared)
    assert sensor.radius == pytest.approx(3 * math.tan(math.radians(30)))
    assert sensor.white_fraction(sim) == (1.0 if colour else 0.0)
    assert sim.command("i0") == [1.0 if colour else 0.0]


def test_infrared_simmer_radius_model_is_available() -> None:
    data = with_sensor("i0", type="infrared", radius_model="simmer", height=2.0)
    sensor = make_sim(data).robot.sensors["i0"]
    assert isinstance(sensor, Infrared)
    assert sensor.radius == pytest.approx(2 * math.cos(math.radians(30)))


@pytest.mark.parametrize(("height", "expected"), [(1.0, 9.0), (10.0, 15.5)])
def test_block_visibility_depends_on_sensor_height(height: float, expected: float) -> None:
    data = default_data()
    data["sensors"]["u0"]["height"] = height
    sim = make_sim(data)
    assert sim.place_robot(66.0, 18.0, 180.0)
    # u0 is at y = 15.5 facing up: the block's face is 9 in away, the wall behind 15.5 in.
    assert sim.command("u0")[0] == pytest.approx(expected, abs=1e-9)


def test_ultrasonic_noise_follows_simmer_percent_error() -> None:
    data = default_data()
    data["sensors"]["u0"]["error"] = 0.01
    sim = make_sim(data, seed=11)
    readings = np.array([sim.command("u0")[0] for _ in range(4000)])
    assert readings.mean() == pytest.approx(39.5, abs=0.1)
    assert readings.std() == pytest.approx(2 * 0.01 * 39.5, rel=0.05)


def test_drive_bias_curves_the_path() -> None:
    data = default_data()
    data["drives"]["w0"]["bias"] = {"rotation": 0.2}
    sim = make_sim(data)
    sim.command("w0-10")
    sim.run_until_idle()
    assert sim.robot.pose.heading == pytest.approx(182.0, abs=1e-9)
    assert sim.robot.pose.x != 6.0


def test_rand_bias_draws_a_bias_per_drive_from_the_seed() -> None:
    data = default_data() | {"rand_bias": True, "bias_strength": [0.05, 0.5]}
    first = make_sim(data, seed=1).robot.drives["w0"].bias
    again = make_sim(data, seed=1).robot.drives["w0"].bias
    other = make_sim(data, seed=2).robot.drives["w0"].bias
    assert first == again
    assert first != other
    assert first.rotation != 0.0


def test_infrared_height_may_come_from_the_position() -> None:
    sensor = make_sim(with_sensor("i0", type="infrared", position=[0, 0, 2.0])).robot.sensors["i0"]
    assert isinstance(sensor, Infrared)
    assert sensor.radius == pytest.approx(2 * math.tan(math.radians(30)))
