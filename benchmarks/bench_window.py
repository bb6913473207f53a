"""Frames drawn per second, uncapped, with the lab rover and every sensor's measurement shown.

Off-screen (SDL's dummy video driver): the cost measured is the drawing itself (cached static
layer, dynamic scene, HUD) plus event handling, i.e. everything :meth:`Window.frame` does but
the flip to a real display. Run: ``.venv/bin/python benchmarks/bench_window.py``.
"""

from __future__ import annotations

import os
import time

os.environ.setdefault("SDL_VIDEODRIVER", "dummy")
os.environ.setdefault("PYGAME_HIDE_SUPPORT_PROMPT", "1")

import pygame

from simmer import Simulation
from simmer.ui import Window
from simmer.ui.scene import default_window_size

TARGET_FPS = 1500.0


def measure(frames: int = 3000) -> float:
    """Frames per second over ``frames`` frames of the default scene, the rover driving."""
    sim = Simulation.from_config()  # the lab rover; simulate_list shows all four sensors' rays
    pygame.display.init()
    window = Window(sim, surface=pygame.Surface(default_window_size(sim)))
    sim.command("w0-100")
    for _ in range(100):  # warm up (numba kernels, text cache)
        sim.step()
        window.frame()
    clock = time.perf_counter
    drawing = 0.0
    for _ in range(frames):
        sim.step()
        start = clock()
        window.frame()
        drawing += clock() - start
    window.close()
    return frames / drawing


def main() -> None:
    """Print the frames per second drawn (simulation stepping excluded) against the target."""
    fps = measure()
    verdict = "meets" if fps >= TARGET_FPS else "below"
    print(f"window: {fps:,.0f} frames/s drawn (target {TARGET_FPS:,.0f}: {verdict})")


if __name__ == "__main__":
    main()
