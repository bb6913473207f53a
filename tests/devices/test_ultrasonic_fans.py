"""A robot's ultrasonic sensors are cast together, once a pose: each reads exactly what its
fan cast on its own reads, and what a sensor last measured stays its own."""

from __future__ import annotations

import math

import numpy as np
import pytest

from simmer import Simulation
from simmer.devices import Ultrasonic
from simmer.devices.base import DeviceParams
from simmer.geometry import Pose, cast_fan

from helpers import default_data, make_sim

IDS = ["u0", "u1", "u2", "u3"]


def alone(sim: Simulation, sensor: Ultrasonic) -> tuple[float, Pose, np.ndarray]:
    """The sensor's noise-free reading, its pose and its rays, cast here on their own from
    the device's own ``world_pose`` and ``sees_block`` (what one sensor read before sensors
    were cast together)."""
    s = sensor.settings
    at = sensor.world_pose(sim.robot.pose)
    rays = np.full(s.num_rays, math.inf)
    distance = cast_fan(
        sim.maze.hwall,
        sim.maze.vwall,
        sim.maze.cell,
        sim.maze.segments,
        sim.block.segments,
        sensor.sees_block(sim, at.x, at.y),
        at.x,
        at.y,
        at.heading,
        s.beamwidth,
        s.max_range,
        rays,
    )
    reading = s.max_range if distance == math.inf else min(max(distance, s.min_range), s.max_range)
    return reading, at, rays


def mixed_heights() -> Simulation:
    """The default rover with its sensors at different heights: below the block's top, above
    it (whether it is seen then depends on the distance), and unset (the block's side)."""
    data = default_data()
    data["sensors"]["u1"]["height"] = 2.5
    data["sensors"]["u2"]["height"] = 4.0
    del data["sensors"]["u3"]["height"]
    data["sensors"]["u3"]["beamwidth"] = 40.0
    return make_sim(data)


def test_each_sensor_reads_what_its_fan_cast_alone_reads_at_random_poses() -> None:
    sim = mixed_heights()
    rng = np.random.default_rng(36)
    sensors = [sim.robot.devices[i] for i in IDS]
    checked = 0
    for _ in range(400):
        sim.block.place(float(rng.uniform(3, 93)), float(rng.uniform(3, 45)), 0.0)
        sim.robot.pose = Pose(
            float(rng.uniform(1, 95)), float(rng.uniform(1, 47)), float(rng.uniform(0, 360))
        )
        readings = sim.command(",".join(IDS))
        for sensor, reading in zip(sensors, readings, strict=True):
            assert isinstance(sensor, Ultrasonic)
            expected, at, rays = alone(sim, sensor)
            assert reading == expected
            assert sensor.last_origin == (at.x, at.y)
            assert sensor.last_heading == at.heading
            assert np.array_equal(sensor.rays, rays)
            checked += 1
    assert checked == 1600


def test_sensors_read_one_at_a_time_in_any_order_read_as_cast_alone() -> None:
    # a pose casts every fan when several were read at the pose before, else each fan when it
    # is first read: both ways, in any order, the readings are a fan's cast alone
    sim = mixed_heights()
    rng = np.random.default_rng(37)
    checked = 0
    for _ in range(300):
        sim.robot.pose = Pose(
            float(rng.uniform(1, 95)), float(rng.uniform(1, 47)), float(rng.uniform(0, 360))
        )
        chosen = rng.permutation(IDS)[: rng.integers(1, 5)]
        for sensor_id in chosen:
            sensor = sim.robot.devices[sensor_id]
            assert isinstance(sensor, Ultrasonic)
            assert sim.command(str(sensor_id)) == [alone(sim, sensor)[0]]
            checked += 1
    assert checked > 600


def test_moving_the_block_alone_is_seen_at_once() -> None:
    sim = make_sim()
    assert sim.place_robot(66.0, 18.0, 180.0)
    assert sim.command("u0")[0] == pytest.approx(9.0, abs=1e-9)  # the block's face
    sim.block.place(90.0, 42.0, 0.0)  # out of the way; the robot has not moved
    assert sim.command("u0")[0] == pytest.approx(15.5, abs=1e-9)  # the wall behind it


def test_a_sensor_keeps_the_rays_it_measured_while_the_others_read_on() -> None:
    data = default_data()
    data["simulate_list"] = []  # only what the test reads
    sim = make_sim(data)
    u0 = sim.robot.devices["u0"]
    assert isinstance(u0, Ultrasonic)
    sim.command("u0")
    measured = (u0.last_origin, u0.last_heading, u0.rays.copy())
    sim.command("w0-6")
    sim.step(30)
    sim.command("u1")  # casts every fan from the new pose
    assert (u0.last_origin, u0.last_heading) == measured[:2]
    assert np.array_equal(u0.rays, measured[2])
    sim.command("u0")
    assert u0.last_origin != measured[0]


class Sweeping(Ultrasonic):
    """A sensor on a servo: it turns itself 30 degrees a step."""

    def update(self, world: object) -> None:
        self.rotation = (self.rotation + 30.0) % 360.0


def test_a_subclass_that_turns_itself_reads_where_it_faces_now() -> None:
    sim = make_sim()
    params = sim.robot.devices["u0"].params
    assert isinstance(params, DeviceParams)
    sweeping = Sweeping("s0", params, sim.stream("device:s0"))
    seen = set()
    for _ in range(12):
        sweeping.update(sim)
        reading = sweeping.simulate(0.0, sim)
        assert reading == alone(sim, sweeping)[0]
        seen.add(reading)
    assert len(seen) > 3  # it did look around
    u0 = sim.robot.devices["u0"]
    assert isinstance(u0, Ultrasonic)
    assert sim.command("u0")[0] == alone(sim, u0)[0]  # the robot's own sensors unaffected
