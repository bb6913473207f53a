"""Localization tools: lookup tables, expected readings, showing and drawing a belief.

1. ``simmer table``'s work for the lab maze at 1 in x 1 degree for the four ultrasonic sensors
   (96 x 48 positions x 360 headings x 4 = 6.6 million fans of 7 rays): the first call (Numba
   compiles, or loads its cache) and the best of three after it. Target: under 10 s.
2. ``Simulation.expected`` at 1,000 random poses: microseconds a pose.
3. ``robot.show`` of 2,000 particles over the persistent protocol: milliseconds a show (the
   client's formatting, the line, the simulator's reading and the event).
4. Drawing a frame off-screen with 2,000 particles shown, against none: milliseconds a frame
   (the window draws at 60 frames a second: 16.7 ms a frame). Target: under 8 ms.

Run: ``.venv/bin/python benchmarks/bench_localization.py``.
"""

from __future__ import annotations

import os
import statistics
import time

os.environ.setdefault("SDL_VIDEODRIVER", "dummy")
os.environ.setdefault("PYGAME_HIDE_SUPPORT_PROMPT", "1")

import numpy as np

from simmer import Simulation
from simmer.client import connect
from simmer.options import RunOptions
from simmer.runner import Runner
from simmer.transport import Transports
from simmer.ui.offscreen import OffscreenRenderer
from simmer.view.maker import LocalControls, SnapshotMaker
from simmer.view.snapshot import StaticScene
from simmer.world.expected import parse_headings, table

TARGET_TABLE_SECONDS = 10.0
TARGET_FRAME_MS = 8.0


def particles(count: int, seed: int = 0) -> np.ndarray:
    """``count`` particles spread over the lab maze."""
    rng = np.random.default_rng(seed)
    return np.column_stack(
        (
            rng.uniform(0, 96, count),
            rng.uniform(0, 48, count),
            rng.uniform(0, 360, count),
            rng.uniform(0, 1, count),
        )
    )


def bench_table() -> tuple[float, float, int]:
    """(first, best of three after it) seconds, and the readings."""
    sim = Simulation.from_config()
    headings = parse_headings("0:360:1")
    start = time.perf_counter()
    *_, readings = table(sim, 1.0, headings)
    first = time.perf_counter() - start
    runs = []
    for _ in range(3):
        start = time.perf_counter()
        table(sim, 1.0, headings)
        runs.append(time.perf_counter() - start)
    return first, min(runs), int(readings.size)


def bench_expected() -> float:
    """Microseconds a pose, 1,000 random poses, the four ultrasonic sensors."""
    sim = Simulation.from_config()
    poses = particles(1000)[:, :3]
    sim.expected(poses)
    start = time.perf_counter()
    for _ in range(20):
        sim.expected(poses)
    return (time.perf_counter() - start) / 20 / 1000 * 1e6


def bench_show(shows: int = 50) -> float:
    """Milliseconds a show of 2,000 particles over the persistent protocol, each one kept (the
    simulation runs as fast as it can, and a show waits for the next simulated 0.05 s)."""
    import threading

    sim = Simulation.from_config()
    runner = Runner(sim, speed=None)
    stop = threading.Event()
    link = Transports(runner.bus, sim.config, RunOptions.free_ports())
    thread = threading.Thread(target=runner.run, kwargs={"stop_event": stop})
    cloud = particles(2000)
    with link:
        thread.start()
        try:
            with connect(port=link.stream.port) as robot:
                robot.show(cloud)
                times = []
                for _ in range(shows):
                    robot.link.clock("!sleep 0.05")  # type: ignore[attr-defined]
                    start = time.perf_counter()
                    cut = robot.show(cloud)
                    times.append(time.perf_counter() - start)
                    assert cut == 0, "a show was dropped: the benchmark would time the drop"
        finally:
            stop.set()
            thread.join()
            runner.bus.close()
    return statistics.median(times) * 1000


def bench_frame(frames: int = 300) -> tuple[float, float]:
    """Milliseconds a frame drawn off-screen with 2,000 particles shown, and with none."""
    from simmer.client import Client
    from simmer.runner import LocalLink

    sim = Simulation.from_config()
    maker = SnapshotMaker(sim)
    robot = Client(LocalLink(sim), lockstep=True)
    robot.show(particles(2000), pose=(20, 30, 45), cov=[[9, 3], [3, 4]], cells=np.ones((4, 8)) / 32)
    canvas = OffscreenRenderer(StaticScene.of(sim))
    controls = LocalControls(sim)
    result = []
    for shown in (True, False):
        canvas.show_belief = shown
        canvas.draw(maker.snapshot(controls))
        start = time.perf_counter()
        for _ in range(frames):
            sim.step()
            canvas.draw(maker.snapshot(controls))
        result.append((time.perf_counter() - start) / frames * 1000)
    return result[0], result[1]


def main() -> None:
    first, best, count = bench_table()
    mark = "ok" if best < TARGET_TABLE_SECONDS else "SLOW"
    print(
        f"table, lab maze 1 in x 1 deg x 4 ultrasonic ({count:,} readings): first {first:.2f} s "
        f"(Numba compiles or loads its cache), then {best:.2f} s "
        f"[{mark}, target < {TARGET_TABLE_SECONDS:g} s]"
    )
    print(f"expected at 1,000 random poses, 4 ultrasonic sensors: {bench_expected():.2f} us a pose")
    print(f"robot.show of 2,000 particles over TCP: {bench_show():.1f} ms a show (median)")
    shown, bare = bench_frame()
    mark = "ok" if shown < TARGET_FRAME_MS else "SLOW"
    print(
        f"frame drawn off-screen with 2,000 particles: {shown:.2f} ms ({1000 / shown:.0f} "
        f"frames/s), without: {bare:.2f} ms [{mark}, target < {TARGET_FRAME_MS:g} ms; the "
        "window draws 60 frames/s]"
    )


if __name__ == "__main__":
    main()
