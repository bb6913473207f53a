"""A LiDAR's scan is drawn in the window and in a video's frames: its points, where its beams
met the walls."""

from __future__ import annotations

import numpy as np
import pygame

from simmer import Simulation
from simmer.devices import Lidar
from simmer.ui import Bridge, Window
from simmer.ui.offscreen import OffscreenRenderer
from simmer.ui.scene import default_window_size
from simmer.view.snapshot import StaticScene

from helpers import EXAMPLES


def test_the_window_and_a_video_frame_draw_the_scans_points() -> None:
    sim = Simulation.from_config(EXAMPLES / "lidar_rover.toml", seed=4)
    sim.step(12)
    device = sim.robot.devices["l0"]
    assert isinstance(device, Lidar)
    color = device.settings.point_color
    size = default_window_size(sim)
    bridge = Bridge(sim)
    window = Window(bridge, surface=pygame.Surface(size))
    try:
        window.draw()
        offscreen = OffscreenRenderer(StaticScene.of(sim), pygame.Surface(size, 0, 32))
        offscreen.draw(bridge.latest)
        for surface in (window.screen, offscreen.surface):
            pixels = pygame.surfarray.array3d(surface)
            drawn = int(np.all(pixels == color, axis=2).sum())
            assert drawn > 500  # hundreds of points, a ring of pixels each
    finally:
        window.close()
        bridge.close()
