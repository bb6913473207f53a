"""One random stream per source (issue 10): a device's noise depends on the run's seed and its
own id only, so adding a device, or polling a drive, never shifts another device's noise."""

from __future__ import annotations

import math

from simmer import Simulation
from simmer.devices.base import NOISE_BLOCK
from simmer.devices.sensors import Ultrasonic

from helpers import make_sim, noisy_data


def readings(sim: Simulation, polls: bool = False) -> list[float]:
    """Drive the lab's first legs, reading u0/u1 on the way (with idle polls if asked)."""
    seen: list[float] = []
    for move in ("w0-12", "r0-90", "w0-12"):
        seen += sim.command("u0,u1")
        assert sim.command(move) == [math.inf]
        if polls:
            assert math.isnan(sim.command("w0-3")[0])  # refused: the drive is busy
        while sim.robot.any_drive_moving:
            sim.step()
            if polls:
                sim.command("w0-0")
        seen += [sim.robot.pose.x, sim.robot.pose.y, sim.robot.pose.heading]
    return seen


def test_same_seed_same_run_other_seed_other_run() -> None:
    assert readings(make_sim(noisy_data(), seed=4)) == readings(make_sim(noisy_data(), seed=4))
    assert readings(make_sim(noisy_data(), seed=4)) != readings(make_sim(noisy_data(), seed=5))


def test_adding_a_sensor_does_not_change_the_others_noise() -> None:
    more = noisy_data()
    more["sensors"]["g0"] = {"type": "gyroscope", "error": 0.2, "bias": 0.1}
    more["sensors"]["c0"] = {"type": "compass", "error": 0.01}
    with_gyro = make_sim(more, seed=9)
    assert readings(with_gyro) == readings(make_sim(noisy_data(), seed=9))


def test_polls_and_refused_drives_draw_nothing() -> None:
    polled = readings(make_sim(noisy_data(), seed=3), polls=True)
    assert polled == readings(make_sim(noisy_data(), seed=3))


def test_drawn_biases_come_from_their_own_streams() -> None:
    data = noisy_data() | {"rand_bias": True, "bias_strength": [0.05, 0.5]}
    first = make_sim(data, seed=11).robot.drives["w0"].bias
    more = data | {"sensors": {**data["sensors"], "g0": {"type": "gyroscope"}}}
    assert make_sim(more, seed=11).robot.drives["w0"].bias == first
    assert make_sim(data, seed=12).robot.drives["w0"].bias != first


def test_block_drawn_noise_is_the_scalar_draws_in_order() -> None:
    """A built-in device draws its noise in blocks (issue 36): the values the scalar draws of
    earlier versions gave, in their order, across block boundaries, so recorded runs replay."""
    sim = make_sim(noisy_data(), seed=11)
    u0 = sim.robot.devices["u0"]
    count = 3 * NOISE_BLOCK + 5
    drawn = [u0.gauss() for _ in range(count)]
    stream = sim.stream("device:u0")
    assert drawn == [float(stream.normal(0.0, 2.0)) for _ in range(count)]


def test_a_subclass_of_a_built_in_kind_draws_one_value_at_a_time() -> None:
    """A user's subclass may draw from ``rng`` itself: its stream is not read ahead."""

    class Mine(Ultrasonic):
        pass

    sim = make_sim(noisy_data(), seed=11)
    mine = Mine("m0", sim.robot.devices["u0"].params, sim.stream("device:m0"))
    seen = [mine.gauss(), float(mine.rng.normal(0.0, 2.0)), mine.gauss()]
    stream = sim.stream("device:m0")
    assert seen == [float(stream.normal(0.0, 2.0)) for _ in range(3)]
