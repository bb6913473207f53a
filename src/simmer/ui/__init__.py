"""The simulator window: the only package that imports pygame (DESIGN §1).

:class:`~simmer.ui.window.Window` draws a :class:`~simmer.world.Simulation` and turns keys and
mouse into manual driving, pausing, resetting and dragging; its :meth:`Window.frame` is the
per-frame hook a runner calls. Drawing goes through the small :class:`~simmer.ui.render.Renderer`
interface, so tests can record the draw calls without a window.
"""

from __future__ import annotations

import os

os.environ.setdefault("PYGAME_HIDE_SUPPORT_PROMPT", "1")

from simmer.ui.hud import Stopwatch
from simmer.ui.render import PygameRenderer, RecordingRenderer, Renderer
from simmer.ui.scene import ScenePainter, View
from simmer.ui.window import Window, render_scene, run_window

__all__ = [
    "PygameRenderer",
    "RecordingRenderer",
    "Renderer",
    "ScenePainter",
    "Stopwatch",
    "View",
    "Window",
    "render_scene",
    "run_window",
]
