"""LiDAR benchmark: one 360-beam scan's cost, a rover's steps per second with a LiDAR beside
the same rover without one, and the lab maze's LiDAR table at 1 in.

Run ``python benchmarks/bench_lidar.py`` (or ``python benchmarks/run.py``). A shared machine's
load makes wall-clock figures swing by two or more, so the scan and step figures are CPU time
(``time.process_time``), each the least of REPEATS rounds taken in turns (the rovers one after
the other in each round, so each sees the same load), after a warm-up that compiles (or loads
from cache) the Numba kernels. The table is wall-clock, as a user waits for it.
"""

from __future__ import annotations

import copy
import time
import tomllib
from collections.abc import Callable
from importlib.resources import files
from typing import Any

from simmer import Simulation
from simmer.config import config_from_dict
from simmer.devices import Lidar
from simmer.devices.lidar import NOISE_SCANS

REPEATS = 21
"""Rounds of each figure: the least is kept, as ``timeit`` does (a round a neighbour slowed
says nothing of the code; a median of 7 still swung the step ratio from 0.76 to 1.26)."""
TARGETS = {
    "scan_us": 30.0,  # stretch 10
    "steps_ratio": 0.9,
    "table_s": 2.0,
}
QUIET = {"range_error": 0, "range_error_proportional": 0, "angular_jitter": 0, "dropout": 0}
"""A LiDAR's settings with every noise off."""
NEVER = {"scan_rate": 0.001}
"""A LiDAR whose first revolution ends after 1,000 s: in a benchmark's run it records the
robot's pose each step and never scans."""


def rover(lidar: bool, settings: dict[str, Any] | None = None) -> Simulation:
    """The built-in lab rover, with an RPLidar on top (``lidar``: the defaults, ``settings``
    changed) or without."""
    text = files("simmer").joinpath("data/default.toml").read_text(encoding="utf-8")
    data: dict[str, Any] = copy.deepcopy(tomllib.loads(text))
    if lidar:
        data["sensors"]["l0"] = {"type": "lidar", "position": [0, 0]} | (settings or {})
    return Simulation(config_from_dict(data, "<bench>", None))


def in_turns(runs: dict[str, Callable[[], object]], count: int) -> dict[str, float]:
    """CPU seconds per call of each of ``runs`` called ``count`` times: the least of REPEATS
    rounds, each round running every one in turn (one warm-up round first)."""
    times: dict[str, list[float]] = {name: [] for name in runs}
    for round_ in range(REPEATS + 1):
        for name, run in runs.items():
            start = time.process_time()
            for _ in range(count):
                run()
            if round_:
                times[name].append((time.process_time() - start) / count)
    return {name: min(values) for name, values in times.items()}


def scan_runs() -> dict[str, Callable[[], object]]:
    """One whole 360-beam scan as the device makes it at the rover's start (the poses, the
    beams cast, the noise applied): noise off, and with the A1M8's noise drawn; the normals'
    draws alone (NOISE_SCANS revolutions' at once; the dropout's few geometric draws left out);
    one ray of the rover's front ultrasonic fan (7 rays a read, the Python call
    included), for comparison: the LiDAR's beams walk the same grid."""
    runs: dict[str, Callable[[], object]] = {}
    for name, settings in (("quiet", QUIET), ("noisy", {})):
        sim = rover(True, settings)
        device = sim.robot.devices["l0"]
        assert isinstance(device, Lidar)
        sim.step()
        runs[name] = lambda d=device, s=sim: d._scan(s, s.time)
    noisy = rover(True).robot.devices["l0"]
    assert isinstance(noisy, Lidar)
    runs["draws"] = noisy._draw  # NOISE_SCANS revolutions' draws: divided by it in main()
    plain = rover(False)
    ultrasonic = plain.robot.devices["u0"]
    runs["ray"] = lambda: ultrasonic.simulate(0.0, plain)
    return runs


WHOLE_SCAN = ",".join(["l0--2", *(f"l0-{float(a)!r}" for a in range(360))])
"""The message ``robot.scan("l0")`` sends for the default LiDAR's 360 beams."""


def step_runs(count: int) -> dict[str, Callable[[], object]]:
    """``count`` steps of the rover driving back and forth: without a LiDAR, with the default
    one (5.5 Hz, the A1M8's noise), with one noise off, with one that never scans (what a
    step costs the LiDAR when no scan is due), and with the default one read whole once a
    revolution, as ``robot.scan("l0")`` does (the message's answering, not its transport)."""
    variants: dict[str, dict[str, Any] | None] = {
        "without": None,
        "with": {},
        "quiet": QUIET,
        "no_scan": NEVER,
        "read": {},
    }
    runs: dict[str, Callable[[], object]] = {}
    for name, settings in variants.items():
        sim = rover(settings is not None, settings)
        device = sim.robot.devices.get("l0")
        reading = name == "read" and isinstance(device, Lidar)

        def run(sim: Simulation = sim, reading: bool = reading, device: Any = device) -> None:
            read = device.number if reading else 0
            for _ in range(count):
                if not sim.robot.any_drive_moving:
                    sim.command("w0-12" if sim.steps % 2 else "w0--12")
                sim.step()
                if reading and device.number != read:
                    read = device.number
                    sim.command(WHOLE_SCAN)

        runs[name] = run
    return runs


def table_seconds() -> float:
    """The lab maze's LiDAR table at 1 in (heading 0; every heading is it rotated), wall-clock
    (the second of two, the first compiling)."""
    from simmer.localize.files import lidar_table

    sim = rover(True)
    lidar_table(sim, 1.0, "l0")
    start = time.perf_counter()
    lidar_table(sim, 1.0, "l0")
    return time.perf_counter() - start


def main() -> dict[str, float]:
    """Measure and print every figure with its target."""
    scan = in_turns(scan_runs(), 500)
    us = {name: value * 1e6 for name, value in scan.items()}
    us["draws"] /= NOISE_SCANS
    figures = {"scan_us": us["quiet"], "scan_noisy_us": us["noisy"], "draws_us": us["draws"]}
    print(
        f"one 360-beam scan, noise off: {us['quiet']:.1f} us of CPU (target <= 30, stretch 10); "
        f"per beam {us['quiet'] * 1e3 / 360:.0f} ns (an ultrasonic read's ray, Python call "
        f"included: {us['ray'] * 1e3 / 7:.0f} ns)"
    )
    print(
        f"  with the A1M8's noise drawn: {us['noisy']:.1f} us, of which the 720 normals (drawn "
        f"{NOISE_SCANS} revolutions at once) {us['draws']:.1f} us"
    )
    count = 2000
    steps = in_turns(step_runs(count), 1)
    per_step = {name: value / count * 1e6 for name, value in steps.items()}
    base = per_step["without"]
    for name in ("with", "quiet", "no_scan", "read"):
        figures[f"step_{name}_us"] = per_step[name] - base
    figures["steps_ratio"] = base / per_step["with"]
    figures["steps_ratio_quiet"] = base / per_step["quiet"]
    figures["steps_ratio_read"] = base / per_step["read"]
    print(
        f"steps per CPU second, the rovers in turn: {1e6 / per_step['with']:,.0f} with a LiDAR "
        f"at 5.5 Hz, {1e6 / base:,.0f} without: ratio {figures['steps_ratio']:.3f} "
        "(target >= 0.9)"
    )
    print(
        f"  the LiDAR's cost a step: {figures['step_with_us']:.2f} us (noise off: "
        f"{figures['step_quiet_us']:.2f} us, ratio {figures['steps_ratio_quiet']:.3f}; a step "
        f"with no scan due: {figures['step_no_scan_us']:.2f} us) against {base:.1f} us a step "
        "without it"
    )
    print(
        f"  with a program reading each scan whole (robot.scan's message answered once a "
        f"revolution): {figures['step_read_us']:.2f} us a step, ratio "
        f"{figures['steps_ratio_read']:.3f}"
    )
    figures["table_s"] = table_seconds()
    print(f"lab maze LiDAR table at 1 in: {figures['table_s']:.2f} s (target < 2)")
    return figures


if __name__ == "__main__":
    main()
