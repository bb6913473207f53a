"""The window: uncapped frames/s drawn, and command round trips while the window runs.

1. Frames per second drawn off-screen with the lab rover and every sensor's measurement shown:
   the cost of drawing a snapshot (cached static layer, dynamic scene, HUD) plus event handling,
   i.e. everything :meth:`Window.frame` does but the flip to a real display. Building the
   snapshot (in the simulation thread) is timed separately.
2. Command round trips (persistent TCP, ``u0``) with the real two-thread window open: pygame
   draws and flips in the main thread while the simulation thread answers. It uses the display
   in ``DISPLAY`` if there is one (e.g. under ``xvfb-run``), else SDL's dummy driver.

Run: ``.venv/bin/python benchmarks/bench_window.py``.
"""

from __future__ import annotations

import os
import statistics
import threading
import time

if not os.environ.get("DISPLAY") and not os.environ.get("WAYLAND_DISPLAY"):
    os.environ.setdefault("SDL_VIDEODRIVER", "dummy")
os.environ.setdefault("PYGAME_HIDE_SUPPORT_PROMPT", "1")

import pygame

from simmer import Simulation
from simmer.client import connect
from simmer.runner import Runner
from simmer.transport import Link
from simmer.ui import Bridge, Window
from simmer.ui.scene import default_window_size

TARGET_FPS = 1500.0
TARGET_LATENCY_MS = 1.0


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
        with Link(runner.bus, sim.config, port_rx=0, port_tx=0, stream_port=0) as link:
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


def main() -> None:
    """Print frames/s drawn (simulation stepping excluded) and round trips with the window."""
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


if __name__ == "__main__":
    main()
