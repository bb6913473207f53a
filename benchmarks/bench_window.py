"""The window: uncapped frames/s drawn, and command round trips while the window runs.

1. Frames per second drawn off-screen with the lab rover and every sensor's measurement shown:
   the cost of drawing a snapshot (cached static layer, dynamic scene, HUD) plus event handling,
   i.e. everything :meth:`Window.frame` does but the flip to a real display. Building the
   snapshot (in the simulation thread) is timed separately.
2. Command round trips (persistent TCP, ``u0``) with the real two-thread window open: pygame
   draws and flips in the main thread while the simulation thread answers. It uses the display
   in ``DISPLAY`` if there is one (e.g. under ``xvfb-run``), else SDL's dummy driver.
3. Video: wall time to record the lab's dead-reckoning run (examples/dead_reckoning.py's
   sequence on the lockstep clock through :class:`~simmer.runner.LocalLink`, about 28
   simulated seconds) at 30 frames/s and the window's size, as MP4 (median of three) and GIF,
   and the megabytes per minute of video.

Run: ``.venv/bin/python benchmarks/bench_window.py``.
"""

from __future__ import annotations

import importlib.util
import os
import statistics
import tempfile
import threading
import time
from pathlib import Path

if not os.environ.get("DISPLAY") and not os.environ.get("WAYLAND_DISPLAY"):
    os.environ.setdefault("SDL_VIDEODRIVER", "dummy")
os.environ.setdefault("PYGAME_HIDE_SUPPORT_PROMPT", "1")

import pygame

from simmer import Simulation
from simmer.client import Client, connect
from simmer.options import RunOptions
from simmer.runner import LocalLink, Runner
from simmer.transport import Transports
from simmer.ui import Bridge, Window
from simmer.ui.scene import default_window_size
from simmer.ui.video import VideoRecorder

TARGET_FPS = 1500.0
TARGET_LATENCY_MS = 1.0
TARGET_VIDEO_SECONDS = 5.0
"""Wall seconds to encode the dead-reckoning run's MP4 (issue 11)."""
EXAMPLE = Path(__file__).resolve().parent.parent / "examples" / "dead_reckoning.py"


def measure(frames: int = 3000) -> float:
    """Frames per second over ``frames`` frames of the default scene, the rover driving."""
    fps, _ = measure_drawing(frames)
    return fps


def measure_drawing(frames: int = 3000) -> tuple[float, float]:
    """(frames drawn per second, snapshots built per second), the rover driving."""
    sim = Simulation.from_config()  # the lab rover; simulate_list shows all four sensors' rays
    pygame.display.init()
    bridge = Bridge(sim)
    window = Window(bridge, surface=pygame.Surface(default_window_size(sim)))
    sim.command("w0-100")
    for _ in range(100):  # warm up (numba kernels, text cache)
        sim.step()
        bridge.sync()
        window.frame()
    clock = time.perf_counter
    drawing = syncing = 0.0
    for _ in range(frames):
        sim.step()
        start = clock()
        bridge.sync()
        middle = clock()
        window.frame()
        drawing += clock() - middle
        syncing += middle - start
    window.close()
    bridge.close()
    return frames / drawing, frames / syncing


def measure_latency(count: int = 600) -> tuple[float, float, float, float, str]:
    """Round trips of ``u0`` with the window open: (median ms, p95 ms, max ms, frames/s shown,
    video driver)."""
    sim = Simulation.from_config()
    runner = Runner(sim, speed=1.0)
    pygame.display.init()
    bridge = Bridge(sim)
    window = Window(bridge)
    driver = pygame.display.get_driver()
    flips = 0
    update = pygame.display.update

    def counted_update(*args: object) -> None:
        nonlocal flips
        flips += 1
        update(*args)

    pygame.display.update = counted_update
    stop = threading.Event()
    rtts: list[float] = []
    span = [0.0, 0.0]

    def program(port: int) -> None:
        try:
            with connect(port=port) as robot:
                time.sleep(1.0)  # let the window settle
                span[0] = time.perf_counter()
                start_flips = flips
                for _ in range(count):
                    t = time.perf_counter()
                    robot.send("u0")
                    rtts.append((time.perf_counter() - t) * 1000)
                    time.sleep(0.003)
                span[1] = (flips - start_flips) / (time.perf_counter() - span[0])
        finally:
            stop.set()

    try:
        with Transports(runner.bus, sim.config, RunOptions.free_ports()) as link:
            thread = threading.Thread(target=program, args=(link.stream.port,))
            thread.start()
            window.run(runner, stop=stop)
            thread.join()
    finally:
        pygame.display.update = update
        runner.bus.close()
        window.close()
        bridge.close()
    rtts.sort()
    p95 = rtts[int(0.95 * len(rtts))]
    return statistics.median(rtts), p95, rtts[-1], span[1], driver


def record_dead_reckoning(path: Path) -> tuple[float, VideoRecorder, float]:
    """Drive the lab's dead-reckoning sequence into a video at ``path``: (wall seconds from the
    recorder's creation to the file's end, the recorder, simulated seconds)."""
    spec = importlib.util.spec_from_file_location("dead_reckoning", EXAMPLE)
    if spec is None or spec.loader is None:
        raise SystemExit(f"cannot load {EXAMPLE}")
    example = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(example)
    sim = Simulation.from_config()
    link = LocalLink(sim)
    robot = Client(link, lockstep=True)
    start = time.perf_counter()
    recorder = VideoRecorder(sim, path, controls=link.runner)
    robot.send(example.SENSORS)
    for drive, amount in example.SEQUENCE:
        robot.drive(drive, amount)
        robot.wait_idle(drive)
        robot.send(example.SENSORS)
    recorder.close()
    return time.perf_counter() - start, recorder, sim.time


def measure_video(suffix: str, runs: int = 3) -> tuple[float, int, float, float]:
    """Recording the dead-reckoning run as ``suffix`` (.mp4, .gif): (median wall seconds,
    frames, simulated seconds, MB per minute of video)."""
    walls = []
    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder) / f"dead_reckoning{suffix}"
        for _ in range(runs):
            path.unlink(missing_ok=True)
            wall, recorder, simulated = record_dead_reckoning(path)
            walls.append(wall)
        megabytes = path.stat().st_size / 1e6
    return statistics.median(walls), recorder.frames, simulated, megabytes / (recorder.seconds / 60)


def main() -> None:
    """Print frames/s drawn (simulation stepping excluded), round trips with the window, and
    the time to record a video."""
    fps, snapshots = measure_drawing()
    verdict = "meets" if fps >= TARGET_FPS else "below"
    print(f"window: {fps:,.0f} frames/s drawn (target {TARGET_FPS:,.0f}: {verdict})")
    print(f"        {snapshots:,.0f} snapshots/s built in the simulation thread")
    median, p95, worst, shown, driver = measure_latency()
    verdict = "meets" if median <= TARGET_LATENCY_MS else "above"
    print(
        f"window open ({driver}): command round trip median {median:.3f} ms, p95 {p95:.3f} ms, "
        f"max {worst:.2f} ms (target median {TARGET_LATENCY_MS:g} ms: {verdict}); "
        f"{shown:.0f} frames/s shown"
    )
    wall, frames, simulated, rate = measure_video(".mp4")
    verdict = "meets" if wall < TARGET_VIDEO_SECONDS else "above"
    print(
        f"video: dead-reckoning run ({simulated:.1f} s simulated, {frames} frames at 30/s, "
        f"{default_window_size(Simulation.from_config())}) as MP4 in {wall:.2f} s wall, median "
        f"of 3 (target {TARGET_VIDEO_SECONDS:g} s: {verdict}); {rate:.1f} MB per minute of video"
    )
    wall, frames, _, rate = measure_video(".gif", runs=1)
    print(f"       the same as GIF: {wall:.2f} s wall, {rate:.1f} MB per minute of video")


if __name__ == "__main__":
    main()
