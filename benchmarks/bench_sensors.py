"""The 2024-25 teams' sensors: what a time-of-flight read costs beside an ultrasonic one, and
what an IMU and two encoders (updated every step) cost a rover's steps per second.

Run ``python benchmarks/bench_sensors.py`` (or ``python benchmarks/run.py``). Figures are
wall-clock on this machine, each the best of several repeats after a warm-up (which also
compiles or loads the Numba kernels).
"""

from __future__ import annotations

import copy
import time
import tomllib
from collections.abc import Callable
from importlib.resources import files
from pathlib import Path
from typing import Any

import numpy as np

from simmer import Simulation
from simmer.config import config_from_dict
from simmer.geometry import Pose

REPEATS = 5
READS = 20_000
STEPS = 20_000
TARGETS = {
    "tof_to_ultrasonic": 1.0,
    "motion_sensors_steps_ratio": 0.7,
}
"""A ToF read (3 rays) costs no more than an ultrasonic one (7 rays: a read's cost is mostly
the call, not the rays); an IMU and two encoders, updated every step of a turning rover, keep
at least 0.7 of its steps per second (the IMU keeps the step's motion and works its readings
out when read; the encoders add up their wheel's turn every step)."""


def rover(motion: bool = False) -> Simulation:
    """The built-in lab rover (noise on) with a VL53L0X on its nose; ``motion``: an IMU and
    two encoders too."""
    text = files("simmer").joinpath("data/default.toml").read_text(encoding="utf-8")
    data: dict[str, Any] = copy.deepcopy(tomllib.loads(text))
    data["simulate_list"] = []
    data["sensors"]["u0"]["error"] = 0.02
    data["sensors"]["t0"] = {"type": "tof", "position": [0, 2.5]}
    if motion:
        data["sensors"] |= {
            "i0": {"type": "imu"},
            "e0": {"type": "encoder", "wheel": "left", "slip": 0.02},
            "e1": {"type": "encoder", "wheel": "right", "slip": 0.02},
        }
    return Simulation(config_from_dict(data, "<bench>", Path.cwd()), seed=1)


def best(run: Callable[[], None]) -> float:
    """The shortest of :data:`REPEATS` timings of ``run``, in seconds."""
    run()  # warm-up
    times = []
    for _ in range(REPEATS):
        start = time.perf_counter()
        run()
        times.append(time.perf_counter() - start)
    return min(times)


def read_cost(sim: Simulation, sensor: str) -> float:
    """Microseconds a read of ``sensor`` costs the simulation (its ``simulate``, the rays and
    the noise), at random poses in the maze's open cells, less the cost of placing the robot."""
    rng = np.random.default_rng(2)
    maze = sim.maze
    poses = [
        Pose(float(x), float(y), float(h))
        for x, y, h in zip(
            rng.uniform(0, maze.width, READS),
            rng.uniform(0, maze.height, READS),
            rng.uniform(0, 360, READS),
            strict=True,
        )
    ]
    robot = sim.robot
    device = robot.sensors[sensor]

    def reads() -> None:
        for pose in poses:
            robot.pose = pose
            device.simulate(0.0, sim)

    def places() -> None:
        for pose in poses:
            robot.pose = pose

    return (best(reads) - best(places)) / READS * 1e6


def steps_per_second(sim: Simulation) -> float:
    """Steps a second of a rover driving a long turn, reading nothing."""
    sim.command("r0-360000")  # moving every step: the encoders' dearest case
    return STEPS / best(lambda: sim.step(STEPS))


def main() -> None:
    """Print the figures and their ratios against :data:`TARGETS`."""
    sim = rover()
    ultrasonic = read_cost(sim, "u0")
    tof = read_cost(sim, "t0")
    ratio = tof / ultrasonic
    print("sensors (the 2024-25 teams')")
    print(f"  ultrasonic read (7 rays):        {ultrasonic:8.2f} us (its simulate())")
    print(f"  time-of-flight read (3 rays):    {tof:8.2f} us")
    target = TARGETS["tof_to_ultrasonic"]
    print(f"  tof / ultrasonic:                {ratio:8.2f}   (target <= {target})")
    bare = steps_per_second(rover())
    moving = steps_per_second(rover(motion=True))
    steps_ratio = moving / bare
    print(f"  steps/s, rover:                  {bare:8.0f}")
    print(f"  steps/s, with an IMU, 2 encoders:{moving:8.0f}")
    print(
        f"  ratio:                           {steps_ratio:8.2f}   "
        f"(target >= {TARGETS['motion_sensors_steps_ratio']})"
    )


if __name__ == "__main__":
    main()
