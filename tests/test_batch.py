"""The batched simulator (issue 36): robot i of a batch is a single Simulation seeded the same
way, bit for bit, with noise on; the particle filter's model agrees with the simulator."""

from __future__ import annotations

import dataclasses
import importlib.util
import math
from typing import Any

import numpy as np
import pytest

from simmer import Simulation, load_config, with_overrides
from simmer.batch import NOISE_BLOCK, Batch, BatchError, Model

from helpers import EXAMPLES, make_config, noisy_data

COMMANDS = ["w0", "r0"]


def random_commands(rng: np.random.Generator, n: int) -> tuple[np.ndarray, np.ndarray]:
    """Per robot: a drive index (-1 none, most steps) and an amount, as a random program."""
    drive = np.where(rng.random(n) < 0.08, rng.integers(0, 2, n), -1)
    amount = np.where(drive == 0, rng.uniform(-8, 12, n), rng.uniform(-180, 180, n))
    return drive, amount


def single_run(config, seed, drives, amounts, sensors):
    """A Simulation driven as the batch drives robot i: its poses and readings per step."""
    sim = Simulation(config, seed=seed)
    names = [f"{d}" for d in ("w0", "r0")]
    poses, readings, replies = [], [], []
    for d, a in zip(drives, amounts, strict=True):
        reply = math.nan
        if d >= 0:
            reply = sim.command(f"{names[d]}-{float(a)!r}")[0]
        sim.step()
        replies.append(reply)
        poses.append(tuple(sim.robot.pose))
        readings.append([sim.robot.devices[s].reading for s in sensors])
    return np.array(poses), np.array(readings), np.array(replies), sim


@pytest.mark.slow
def test_robot_i_of_a_batch_of_64_is_the_simulation_with_its_seed() -> None:
    """64 seeds, 1,000 steps of random commands, noise on: identical poses and readings."""
    data = noisy_data()
    data["rand_bias"] = True
    data["bias_strength"] = [0.02, 0.2]
    config = make_config(data)
    seeds = list(range(1000, 1064))
    batch = Batch(config, seeds)
    assert batch.drive_ids == ("w0", "r0")
    rng = np.random.default_rng(7)
    steps = 1000
    drives = np.empty((steps, 64), dtype=np.int64)
    amounts = np.empty((steps, 64))
    poses = np.empty((steps, 64, 3))
    readings = np.empty((steps, 64, len(batch.sensor_ids)))
    replies = np.empty((steps, 64))
    for t in range(steps):
        drives[t], amounts[t] = random_commands(rng, 64)
        replies[t] = batch.step(drives[t], amounts[t])
        poses[t] = batch.poses
        readings[t] = batch.readings
    for i in range(64):
        p, r, y, sim = single_run(config, seeds[i], drives[:, i], amounts[:, i], batch.sensor_ids)
        np.testing.assert_array_equal(poses[:, i], p)
        np.testing.assert_array_equal(readings[:, i], r)
        np.testing.assert_array_equal(np.isinf(replies[:, i]), np.isinf(y))
        assert batch.collisions[i] == sim.collisions
        assert batch.blocked_steps[i] == sim.blocked_steps
    assert batch.collisions.sum() > 0  # the random programs do hit walls
    # the noise really is on and differs per robot
    assert len({tuple(np.round(poses[-1, i], 6)) for i in range(64)}) == 64


def test_a_short_batch_matches_every_robot() -> None:
    """Every robot of a small batch, past a noise block's refill, with noise on."""
    config = make_config(noisy_data())
    seeds = [3, 5, 8, 13]
    batch = Batch(config, seeds)
    rng = np.random.default_rng(1)
    steps = NOISE_BLOCK + 40
    record = []
    drives, amounts = [], []
    for _ in range(steps):
        d, a = random_commands(rng, len(seeds))
        drives.append(d)
        amounts.append(a)
        batch.step(d, a)
        record.append((batch.poses.copy(), batch.readings.copy()))
    drives_a, amounts_a = np.array(drives), np.array(amounts)
    for i, seed in enumerate(seeds):
        p, r, _, _ = single_run(config, seed, drives_a[:, i], amounts_a[:, i], batch.sensor_ids)
        np.testing.assert_array_equal(np.array([rec[0][i] for rec in record]), p)
        np.testing.assert_array_equal(np.array([rec[1][i] for rec in record]), r)


def test_steps_at_once_equal_steps_one_by_one() -> None:
    config = make_config(noisy_data())
    a = Batch(config, [1, 2])
    b = Batch(config, [1, 2])
    drive = np.array([0, 1])
    amount = np.array([10.0, 90.0])
    a.step(drive, amount, steps=300)
    b.step(drive, amount)
    for _ in range(299):
        b.step()
    np.testing.assert_array_equal(a.poses, b.poses)
    np.testing.assert_array_equal(a.readings, b.readings)
    assert (a.steps == 300).all()


def test_reset_gives_the_start_again_and_a_new_seed_new_noise() -> None:
    config = make_config(noisy_data())
    batch = Batch(config, [4, 4])
    batch.command(["w0-10", "w0-10"])
    assert batch.moving.all()
    batch.step(steps=199)
    assert not batch.moving.any()
    first = batch.poses.copy()
    np.testing.assert_array_equal(first[0], first[1])  # same seed, same run
    batch.reset([1], [9])
    assert batch.steps[1] == 0
    np.testing.assert_array_equal(batch.poses[1], Simulation(config, seed=9).robot.pose)
    batch.command([None, "w0-10"], steps=200)
    assert not np.array_equal(batch.poses[1], first[0])


def test_bad_batches_and_commands_say_what_to_fix() -> None:
    config = make_config(noisy_data())
    with pytest.raises(BatchError, match="batch_robots"):
        Batch(config, [])
    with pytest.raises(BatchError, match="not an ultrasonic sensor"):
        Batch(config, [1], sensors=["w0"])
    batch = Batch(config, [1])
    with pytest.raises(BatchError, match="threads must be 1 to"):
        Batch(config, [1], threads=0)
    with pytest.raises(BatchError, match="the form is drive-amount"):
        batch.command(["w0"])
    with pytest.raises(BatchError, match="no drive 'z9'"):
        batch.command(["z9-3"])
    with pytest.raises(BatchError, match="finite"):
        batch.step(np.array([0]), np.array([math.inf]))
    with pytest.raises(BatchError, match="one per robot"):
        batch.step(np.array([0, 0]), np.array([1.0, 1.0]))


def test_the_model_reads_what_the_simulation_expects() -> None:
    """Noise-free readings at many poses equal Simulation.expected's."""
    config = make_config(noisy_data())
    sim = Simulation(config, seed=1)
    model = Model(config)
    rng = np.random.default_rng(2)
    poses = np.column_stack(
        (rng.uniform(2, 94, 100), rng.uniform(2, 46, 100), rng.uniform(0, 360, 100))
    )
    mine = model.expected(poses)
    theirs = sim.expected(poses, list(model.sensor_ids))
    np.testing.assert_allclose(mine, theirs, rtol=0, atol=1e-9)
    noisy = model.read(poses, np.random.default_rng(3))
    assert noisy.shape == mine.shape
    assert not np.array_equal(noisy, mine)
    # the sensor's error is 0.05: the noise is about 10% of the distance
    spread = np.std((noisy - mine) / mine)
    assert 0.05 < spread < 0.2


def test_the_model_moves_particles_as_the_drive_does() -> None:
    """No noise: every particle ends where the single simulation's robot does."""
    data = noisy_data()
    data["drives"]["w0"]["error"] = {"x": 0.0, "y": 0.0, "rotation": 0.0}
    config = make_config(data)
    sim = Simulation(config, seed=1)
    start = np.array(sim.robot.pose)
    sim.command("w0-10")
    sim.run_until_idle()
    model = Model(config)
    moved = model.move(np.tile(start, (5, 1)), "w0", 10.0)
    for row in moved:
        np.testing.assert_allclose(row, tuple(sim.robot.pose), atol=1e-9)
    noisy = Model(make_config(noisy_data())).move(
        np.tile(start, (200, 1)), "w0", 10.0, np.random.default_rng(4)
    )
    assert np.std(noisy[:, 1]) > 0.1  # the drive's error spreads them


def test_the_free_space_shortcut_changes_no_move() -> None:
    """Model.move skips the collision test where the robot is provably clear of every wall and
    the block: particles all over the maze (against walls, by the block, with bias and error)
    end exactly where testing every step puts them."""
    data = noisy_data()
    data["drives"]["w0"]["bias"] = {"x": 0.01, "y": 0.0, "rotation": 0.3}
    model = Model(make_config(data))
    layout = model._layout
    assert len(layout.free) > 0
    assert layout.field.size > 0
    tested = Model(make_config(data))
    tested._layout = dataclasses.replace(layout, free=np.zeros((0, 2)))  # every step tested
    rng = np.random.default_rng(11)
    rows, cols = layout.maze.solid.shape
    cell = layout.maze.cell
    n = 600
    poses = np.column_stack(
        (
            rng.uniform(0.0, cols * cell, n),
            rng.uniform(0.0, rows * cell, n),
            rng.uniform(0.0, 360.0, n),
        )
    )
    poses[:40, :2] = model._block_xy[0] + rng.normal(0.0, 4.0, (40, 2))  # by the block
    blocked = 0
    for drive, amount in (("w0", 12.0), ("w0", -7.0), ("r0", 90.0), ("r0", -200.0)):
        fast = model.move(poses, drive, amount, np.random.default_rng(5))
        slow = tested.move(poses, drive, amount, np.random.default_rng(5))
        np.testing.assert_array_equal(fast, slow)
        blocked += int((np.abs(fast - poses).sum(axis=1) == 0).sum())
        poses = fast
    assert blocked > 50  # many particles met a wall on the way


def load_example(name: str) -> Any:
    """An example program as a module (examples/ is not a package)."""
    spec = importlib.util.spec_from_file_location(name, EXAMPLES / f"{name}.py")
    assert spec is not None
    assert spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


@pytest.mark.slow
def test_the_particle_filter_example_localizes_on_the_lab_maze() -> None:
    """examples/particle_filter.py, with a noisy Simulation as the robot: from not knowing
    where it starts, the estimate ends within 3 in of the truth."""
    example = load_example("particle_filter")
    config = make_config(noisy_data())
    sim = Simulation(config, seed=5)
    model = Model(config, ["u0", "u1", "u2", "u3"])

    def read() -> list[float]:
        return sim.command("u0,u1,u2,u3")

    def drive(name: str, amount: float) -> None:
        sim.command(f"{name}-{amount!r}")
        sim.run_until_idle()

    f = example.localize(read, drive, model, moves=12)
    x, y, heading = f.estimate()
    truth = sim.robot.pose
    assert math.hypot(x - truth.x, y - truth.y) < 3.0, (f.estimate(), truth)
    assert abs((heading - truth.heading + 180) % 360 - 180) < 15
    assert f.spread() < 3.0


@pytest.mark.slow
def test_the_particle_filter_keeps_every_place_that_matches_then_fewer_particles() -> None:
    """The example's KLD-sampling and staged first reading: from the localization page's start
    (1,6,90, 2% noise) its first reading keeps particles at the three places whose readings
    match (the page's picture), about 1,000 of them; once one place is left the count falls to
    the fewest; and for eight seeds (the robot's and the filter's) it ends within 2 in."""
    example = load_example("particle_filter")
    noise = {f"sensors.u{k}.error": 0.02 for k in range(4)} | {"scenario.start": "1,6,90"}
    config = with_overrides(load_config(EXAMPLES / "lab1_rover.toml"), noise)
    model = Model(config, ["u0", "u1", "u2", "u3"])
    for seed in range(8):
        sim = Simulation(config, seed=seed)
        counts: list[int] = []
        places: list[set[tuple[int, int]]] = []

        def read(sim: Simulation = sim) -> list[float]:
            return sim.command("u0,u1,u2,u3")

        def drive(name: str, amount: float, sim: Simulation = sim) -> None:
            sim.command(f"{name}-{amount!r}")
            sim.run_until_idle()

        def report(f: Any, counts: list[int] = counts, places: list[Any] = places) -> None:
            cells = np.floor(f.particles[:, :2] / model.cell).astype(int)
            found, many = np.unique(cells, axis=0, return_counts=True)
            counts.append(len(f.particles))
            places.append(
                {(int(x), int(y)) for (x, y), n in zip(found, many, strict=True) if n >= 5}
            )

        f = example.localize(read, drive, model, 12, report, seed=seed)
        assert {(1, 3), (4, 1), (6, 1)} <= places[0], (seed, places[0])
        assert 500 < counts[0] < example.PARTICLES, (seed, counts)
        assert counts[-1] == example.FEWEST, (seed, counts)
        x, y, _ = f.estimate()
        assert math.hypot(x - sim.robot.pose.x, y - sim.robot.pose.y) < 2.0, seed


@pytest.mark.slow  # compiles the threaded kernel (Numba does not cache it)
def test_two_threads_step_the_same_robots() -> None:
    config = make_config(noisy_data())
    one = Batch(config, list(range(40)))
    two = Batch(config, list(range(40)), threads=2)
    rng = np.random.default_rng(9)
    for _ in range(30):
        drive, amount = random_commands(rng, 40)
        one.step(drive, amount, steps=5)
        two.step(drive, amount, steps=5)
    np.testing.assert_array_equal(one.poses, two.poses)
    np.testing.assert_array_equal(one.readings, two.readings)
    np.testing.assert_array_equal(one.collisions, two.collisions)
