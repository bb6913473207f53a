"""LiDAR benchmark: one 360-beam scan's cost, a rover's steps per second with a LiDAR beside
the same rover without one, and the lab maze's LiDAR table at 1 in.

Run ``python benchmarks/bench_lidar.py`` (or ``python benchmarks/run.py``). Figures are
wall-clock on this machine, each the best of several repeats after a warm-up that compiles (or
loads from cache) the Numba kernels; the steps ratio is measured by CPU time too, the two
rovers in turn, as a loaded machine makes the wall-clock ratio swing.
"""

from __future__ import annotations

import copy
import math
import time
import tomllib
from collections.abc import Callable
from importlib.resources import files
from typing import Any

from simmer import Simulation
from simmer.config import config_from_dict
from simmer.devices import Lidar

REPEATS = 5
TARGETS = {
    "scan_us": 30.0,  # stretch 10
    "steps_ratio": 0.9,
    "table_s": 2.0,
}


def rover(lidar: bool, settings: dict[str, Any] | None = None) -> Simulation:
    """The built-in lab rover, with an RPLidar on top (``lidar``: the defaults, ``settings``
    changed) or without."""
    text = files("simmer").joinpath("data/default.toml").read_text(encoding="utf-8")
    data: dict[str, Any] = copy.deepcopy(tomllib.loads(text))
    if lidar:
        data["sensors"]["l0"] = {"type": "lidar", "position": [0, 0]} | (settings or {})
    return Simulation(config_from_dict(data, "<bench>", None))


def best(
    run: Callable[[], None], count: int, clock: Callable[[], float] = time.perf_counter
) -> float:
    """The shortest time of REPEATS runs of ``run`` called ``count`` times, per call, by
    ``clock`` (wall-clock; ``time.process_time``: CPU time)."""
    times = []
    for _ in range(REPEATS):
        start = clock()
        for _ in range(count):
            run()
        times.append((clock() - start) / count)
    return min(times)


def scan_microseconds(quiet: bool, clock: Callable[[], float] = time.perf_counter) -> float:
    """One whole 360-beam scan as the device makes it at the rover's start: the poses, the
    beams cast, and (unless ``quiet``) the noise drawn and applied; by ``clock``."""
    extra = {"range_error": 0, "range_error_proportional": 0, "angular_jitter": 0, "dropout": 0}
    sim = rover(True, extra if quiet else {})
    device = sim.robot.devices["l0"]
    assert isinstance(device, Lidar)
    sim.step()
    return best(lambda: device._scan(sim, sim.time, skew=True), 2000, clock) * 1e6


def ultrasonic_ray_nanoseconds() -> float:
    """One ray of the rover's front ultrasonic fan (7 rays, a read), for comparison: the
    LiDAR's beams walk the same grid, so the two figures move together with the machine's
    load."""
    sim = rover(False)
    device = sim.robot.devices["u0"]
    return best(lambda: device.simulate(0.0, sim), 5000) * 1e9 / 7


def steps_per_second(lidar: bool, count: int = 6000) -> float:
    """Steps a second of the rover driving back and forth, with or without its LiDAR."""
    sim = rover(lidar)

    def run() -> None:
        for _ in range(count):
            if not sim.robot.any_drive_moving:
                sim.command("w0-12" if sim.steps % 2 else "w0--12")
            sim.step()

    run()
    return 1.0 / best(run, 1) * count


def steps_per_cpu_second(count: int = 6000) -> tuple[float, float]:
    """Steps per CPU second of the rover with and without its LiDAR, the two measured in turn
    (best of REPEATS each): on a machine others load, wall-clock figures taken a few seconds
    apart see different shares of the CPU, and CPU time does not."""
    rovers = {True: rover(True), False: rover(False)}
    best_cpu = {True: math.inf, False: math.inf}

    def run(sim: Simulation) -> float:
        start = time.process_time()
        for _ in range(count):
            if not sim.robot.any_drive_moving:
                sim.command("w0-12" if sim.steps % 2 else "w0--12")
            sim.step()
        return time.process_time() - start

    for sim in rovers.values():
        run(sim)  # warm-up
    for _ in range(REPEATS):
        for lidar, sim in rovers.items():
            best_cpu[lidar] = min(best_cpu[lidar], run(sim))
    return count / best_cpu[True], count / best_cpu[False]


def table_seconds() -> float:
    """The lab maze's LiDAR table at 1 in (heading 0; every heading is it rotated)."""
    from simmer.localize.files import lidar_table

    sim = rover(True)
    lidar_table(sim, 1.0, "l0")
    start = time.perf_counter()
    lidar_table(sim, 1.0, "l0")
    return time.perf_counter() - start


def main() -> dict[str, float]:
    """Measure and print every figure with its target."""
    figures = {"scan_us": scan_microseconds(quiet=True)}
    print(f"one 360-beam scan, noise off: {figures['scan_us']:.1f} us (target <= 30, stretch 10)")
    cpu = scan_microseconds(quiet=True, clock=time.process_time)
    print(f"  the same by CPU time: {cpu:.1f} us")
    ray = ultrasonic_ray_nanoseconds()
    print(
        f"  per beam {figures['scan_us'] * 1e3 / 360:.0f} ns; an ultrasonic read's ray, "
        f"Python call included: {ray:.0f} ns"
    )
    noisy = scan_microseconds(quiet=False)
    print(f"one 360-beam scan with the A1M8's noise drawn: {noisy:.1f} us")
    with_lidar, without = steps_per_second(True), steps_per_second(False)
    figures["steps_ratio"] = with_lidar / without
    print(
        f"steps/s with a LiDAR at 5.5 Hz: {with_lidar:,.0f}; without: {without:,.0f}; "
        f"ratio {figures['steps_ratio']:.3f} (target >= 0.9)"
    )
    cpu_with, cpu_without = steps_per_cpu_second()
    figures["steps_ratio_cpu"] = cpu_with / cpu_without
    print(
        f"steps per CPU second, measured in turn: {cpu_with:,.0f} with; {cpu_without:,.0f} "
        f"without; ratio {figures['steps_ratio_cpu']:.3f} (target >= 0.9)"
    )
    figures["table_s"] = table_seconds()
    print(f"lab maze LiDAR table at 1 in: {figures['table_s']:.2f} s (target < 2)")
    return figures


if __name__ == "__main__":
    main()
