"""The IMU (``imu``) and wheel encoders (``encoder``): a stationary IMU's bias and noise match
its configured figures over a long run, its readings of a known motion are exact with the noise
off, and encoders count a known drive exactly, or within their slip."""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import pytest

from simmer.devices.motion import G_IN_S2
from simmer.geometry import Pose

from helpers import default_data, make_sim, run_sequence

STEPS = 3600  # a minute at 60 steps/s
DT = 1.0 / 60.0
QUIET_IMU = {
    "type": "imu",
    "gyro_noise_density": 0.0,
    "gyro_bias_walk": 0.0,
    "accel_noise_density": [0.0, 0.0],
    "accel_bias_walk": [0.0, 0.0],
}


def sim_with(seed: int | None = 1, **sensors: dict[str, Any]) -> Any:
    """The default rover (no ultrasonic reads every step) with ``sensors`` added."""
    data = default_data()
    data["simulate_list"] = []
    data["sensors"] |= sensors
    return make_sim(data, seed=seed)


def read_every_step(sim: Any, message: str, steps: int = STEPS) -> np.ndarray:
    rows = []
    for _ in range(steps):
        sim.step()
        rows.append(sim.command(message))
    return np.array(rows)


# ----------------------------------------------------------------------------- IMU


def test_a_stationary_imus_bias_and_noise_match_its_figures_over_a_minute() -> None:
    imu = {
        "type": "imu",
        "gyro_noise_density": 0.005,  # the MPU6050's
        "gyro_bias": 0.3,
        "gyro_bias_walk": 0.0,
        "accel_noise_density": [400e-6 * G_IN_S2, 0.5],
        "accel_bias": [1.5, -2.0],
        "accel_bias_walk": [0.0, 0.0],
    }
    readings = read_every_step(sim_with(i0=imu), "i0-0,i0-1,i0-2")
    sd = np.array([0.005, 400e-6 * G_IN_S2, 0.5]) / math.sqrt(DT)  # density / sqrt(dt)
    bias = np.array([0.3, 1.5, -2.0])
    mean_tolerance = 4.0 * sd / math.sqrt(STEPS)
    assert np.all(np.abs(readings.mean(axis=0) - bias) < mean_tolerance)
    # the spread of 3,600 normal draws is within 1.2 % (one sd) of the true one: 6 % is 5 sd
    np.testing.assert_allclose(readings.std(axis=0), sd, rtol=0.06)


def test_an_imus_bias_wanders_at_its_configured_walk_whatever_the_reads() -> None:
    imu = QUIET_IMU | {"gyro_bias_walk": 0.02, "accel_bias_walk": [0.1, 0.0]}
    sim = sim_with(seed=4, i0=imu)
    readings = read_every_step(sim, "i0-0,i0-1,i0-2")
    steps = np.diff(readings, axis=0)  # noise off: each reading is the bias itself
    np.testing.assert_allclose(
        steps[:, :2].std(axis=0), np.array([0.02, 0.1]) * math.sqrt(DT), rtol=0.06
    )
    assert np.all(readings[:, 2] == 0.0)  # no walk on y
    # read ten times less often: the bias at the end is the same
    other = sim_with(seed=4, i0=imu)
    for _ in range(STEPS // 10):
        other.step(10)
        last = other.command("i0-0,i0-1")
    assert last == readings[-1, :2].tolist()


def test_an_imu_reads_a_turn_and_its_mounting_points_centripetal_acceleration() -> None:
    sim = sim_with(i0=QUIET_IMU, i1=QUIET_IMU | {"position": [2.0, 0.0]})
    sim.command("r0-360")  # clockwise in the window at 120 °/s
    sim.step(10)  # past the first step (its velocity jumps from 0)
    rate, ax, ay, rate1, ax1, ay1 = sim.command("i0-0,i0-1,i0-2,i1-0,i1-1,i1-2")
    assert rate == pytest.approx(-120.0, abs=1e-9)  # z up: anticlockwise is positive
    assert rate1 == pytest.approx(-120.0, abs=1e-9)
    assert (ax, ay) == pytest.approx((0.0, 0.0), abs=1e-9)  # at the centre of the turn
    # 2 in toward the robot's left: omega² r toward the centre, on the chip's +x (its right);
    # a 2° step moves it by a chord, not an arc, and turns its velocity by one: twice the ratio
    # of a chord of 2° to its arc
    omega = math.radians(120.0)
    chord = 2.0 * math.sin(math.radians(1.0)) / math.radians(2.0)
    assert ax1 == pytest.approx(omega**2 * 2.0 * chord**2, rel=1e-9)
    assert ay1 == pytest.approx(0.0, abs=1e-9)


def test_an_imu_reads_a_drives_start_and_stop_and_nothing_in_between() -> None:
    sim = sim_with(i0=QUIET_IMU | {"rotation": 90})  # turned: its x axis points ahead
    sim.command("w0-3")  # 6 in/s for 0.5 s
    forward = [sim.command("i0-1,i0-2") for _ in range(31) if sim.step() is None]
    assert forward[0] == pytest.approx([-6.0 / DT, 0.0], abs=1e-9)  # 0 to 6 in/s in one step
    assert forward[10] == pytest.approx([0.0, 0.0], abs=1e-9)
    assert forward[30] == pytest.approx([6.0 / DT, 0.0], abs=1e-9)  # and back to 0


def test_an_imu_names_its_axes_when_asked_for_another() -> None:
    sim = sim_with(i0=QUIET_IMU)
    values = sim.command("i0-3,i0-0.5,i0")
    assert math.isnan(values[0])
    assert math.isnan(values[1])
    assert values[2] == 0.0


# ----------------------------------------------------------------------------- encoders


def encoders(**settings: Any) -> dict[str, dict[str, Any]]:
    return {
        "e0": {"type": "encoder", "wheel": "left"} | settings,
        "e1": {"type": "encoder", "wheel": "right"} | settings,
    }


def counts(distance: float, diameter: float = 2.56, per_rev: float = 360.0) -> int:
    return math.floor(distance / (math.pi * diameter) * per_rev + 1e-6)


def test_encoders_count_a_known_drive_exactly() -> None:
    sim = sim_with(**encoders())
    run_sequence(sim, ["r0-90"])  # clockwise: the left wheel ahead, the right one back
    arc = math.pi / 2.0 * 6.25 / 2.0
    assert sim.command("e0,e1") == [counts(arc), counts(-arc)]
    run_sequence(sim, ["w0-30"])  # along the open row
    assert sim.command("e0,e1") == [counts(30.0 + arc), counts(30.0 - arc)]
    run_sequence(sim, ["w0--12"])
    assert sim.command("e0,e1") == [counts(18.0 + arc), counts(18.0 - arc)]


def test_encoders_with_their_own_wheels_and_counts() -> None:
    sim = sim_with(**encoders(wheel_diameter=3.0, counts_per_rev=1440, track_width=8.0))
    run_sequence(sim, ["r0--180"])
    arc = math.pi * 4.0
    assert sim.command("e0,e1") == [counts(-arc, 3.0, 1440), counts(arc, 3.0, 1440)]


@pytest.mark.parametrize("slip", [0.02, 0.1])
def test_encoders_count_a_known_drive_within_their_slip(slip: float) -> None:
    sim = sim_with(seed=3, **encoders(slip=slip))
    run_sequence(sim, ["w0-36"])  # 360 steps of 0.1 in
    true = 36.0 / (math.pi * 2.56) * 360.0
    left, right = sim.command("e0,e1")
    # each step's slip is slip·|normal|: mean slip·sqrt(2/pi), sd slip·0.603 / sqrt(360) overall
    for value in (left, right):
        assert true <= value <= true * (1.0 + slip)
        assert value / true - 1.0 == pytest.approx(slip * math.sqrt(2 / math.pi), abs=slip * 0.13)
    assert left != right  # each wheel slips by its own draws
    again = sim_with(seed=3, **encoders(slip=slip))
    run_sequence(again, ["w0-36"])
    assert again.command("e0,e1") == [left, right]  # the same seed, the same slip


def test_an_encoder_resets_by_a_command() -> None:
    sim = sim_with(**encoders())
    run_sequence(sim, ["w0-12"])
    assert sim.command("e0-1,e0,e1") == [counts(12.0), 0.0, counts(12.0)]
    run_sequence(sim, ["w0-6"])
    # the count goes on from the wheel's angle at the reset, as a real counter's would
    assert sim.command("e0") == [counts(18.0) - counts(12.0)]
    assert math.isnan(sim.command("e0-2")[0])


def test_a_blocked_robot_turns_no_wheel() -> None:
    sim = sim_with(**encoders())
    sim.robot.pose = Pose(6.0, 42.0, 180.0)
    sim.command("w0-60")  # the wall is 38 in ahead of the nose: blocked there
    sim.run_until_idle()
    left, _ = sim.command("e0,e1")
    assert left == counts(42.0 - sim.robot.pose.y)


@pytest.mark.slow
def test_forty_stationary_imus_drift_apart_as_their_bias_walk_says_over_ten_minutes() -> None:
    ids = [f"{letter}{digit}" for letter in "jkqz" for digit in range(10)]
    walk = QUIET_IMU | {"gyro_bias": 0.5, "gyro_bias_walk": 0.01, "accel_bias_walk": [0.05, 0.0]}
    sim = sim_with(seed=9, **dict.fromkeys(ids, walk))
    sim.step(36_000)  # ten simulated minutes standing still
    rates = np.array(sim.command(",".join(f"{i}-0" for i in ids)))
    accels = np.array(sim.command(",".join(f"{i}-1" for i in ids)))
    # after T seconds each bias has moved by a normal of sd walk * sqrt(T) from its start; the
    # spread of 40 such has a relative error of about 1 / sqrt(80) = 11 %: 35 % is 3 of them
    assert rates.std() == pytest.approx(0.01 * math.sqrt(600.0), rel=0.35)
    assert accels.std() == pytest.approx(0.05 * math.sqrt(600.0), rel=0.35)
    assert abs(rates.mean() - 0.5) < 4 * 0.01 * math.sqrt(600.0) / math.sqrt(40)
    assert np.all(np.array(sim.command(",".join(f"{i}-2" for i in ids))) == 0.0)
