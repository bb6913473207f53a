"""The window draws a time-of-flight sensor's beam after a read (in its beam colour, named in
the legend), and no longer once the read is older than its visible_measurement_time."""

from __future__ import annotations

import numpy as np
import pygame
import pytest

from simmer import Simulation
from simmer.ui import Bridge, Window
from simmer.ui.hud import legend
from simmer.ui.scene import default_window_size
from simmer.view.snapshot import StaticScene

from helpers import EXAMPLES

MAGENTA = (255, 0, 255)


def magenta_pixels(window: Window) -> int:
    window.draw(window.bridge.latest)
    pixels = pygame.surfarray.array3d(window.screen)
    return int(np.all(pixels == MAGENTA, axis=2).sum())


@pytest.mark.slow  # a window and three full draws: about a second
def test_the_window_draws_the_beam_after_a_read_and_not_later() -> None:
    sim = Simulation.from_config(EXAMPLES / "tof_rover.toml")
    assert (MAGENTA, "time-of-flight beams") in legend(StaticScene.of(sim))
    bridge = Bridge(sim)
    window = Window(bridge, surface=pygame.Surface(default_window_size(sim)))
    try:
        swatch = magenta_pixels(window)  # before any read: the legend's swatch alone
        assert swatch > 0
        sim.command("t0,t1,t2")
        bridge.sync()
        # three beams of three rays, the nose's reaching 38 in: hundreds of pixels
        assert magenta_pixels(window) > swatch + 300
        sim.step(40)  # 2/3 s later: past the half second a read is shown for
        bridge.sync()
        assert magenta_pixels(window) == swatch
    finally:
        window.close()
        bridge.close()
