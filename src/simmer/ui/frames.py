"""The gym environments' pictures (``simmer.gym``, which never imports pygame itself): a
simulation's frame as pixels, and a plain window that shows its frames."""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
import pygame

from simmer.ui.window import render_scene

if TYPE_CHECKING:
    from simmer.world import Simulation


def frame_pixels(sim: Simulation) -> np.ndarray:
    """The off-screen renderer's frame of ``sim``, (height, width, 3) RGB pixels."""
    return np.transpose(pygame.surfarray.array3d(render_scene(sim)), (1, 0, 2))


class FrameWindow:
    """A window showing a simulation's frames (``render_mode="human"``), opened on the first."""

    def __init__(self) -> None:
        self._screen: pygame.Surface | None = None

    def show(self, sim: Simulation) -> None:
        """Draw ``sim`` now and show it."""
        surface = render_scene(sim)
        if self._screen is None:
            pygame.display.init()
            self._screen = pygame.display.set_mode(surface.get_size())
            pygame.display.set_caption("SimMeR gym")
        pygame.event.pump()
        self._screen.blit(surface, (0, 0))
        pygame.display.flip()

    def close(self) -> None:
        """Close the window, if one is open."""
        if self._screen is not None:
            pygame.display.quit()
            self._screen = None
