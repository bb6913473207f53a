"""The simulator window and everything that draws: the only package that imports pygame
(DESIGN §1).

:class:`~simmer.ui.window.Window` runs pygame in the main thread and the simulation in its own
thread: it draws immutable :class:`~simmer.view.snapshot.Snapshot` values and turns keys and
mouse into actions (manual driving, pausing, resetting, dragging) that a
:class:`~simmer.ui.bridge.Bridge` applies in the simulation thread, so drawing never delays a
command's reply. Drawing goes through the small :class:`~simmer.ui.render.Renderer` interface, so
tests can record the draw calls without a window. The
:class:`~simmer.ui.offscreen.OffscreenRenderer` draws a snapshot on any surface, without a
display: the window uses it, and so does :class:`~simmer.ui.video.VideoRecorder`, which records
what the window shows into an MP4 or GIF at a fixed rate in simulated time. A recorded run is
played back in :mod:`simmer.ui.replay` (re-simulated by :mod:`simmer.view.replay_model`) and cut
into clips by :mod:`simmer.ui.clip`. What is drawn (snapshots, the path driven, the last
commands, a recording's timeline) is modelled in :mod:`simmer.view`, which a headless run uses
without pygame.
"""

from __future__ import annotations

import os

os.environ.setdefault("PYGAME_HIDE_SUPPORT_PROMPT", "1")

from simmer.ui.bridge import Bridge
from simmer.ui.offscreen import OffscreenRenderer
from simmer.ui.render import PygameRenderer, RecordingRenderer, Renderer
from simmer.ui.scene import ScenePainter, View
from simmer.ui.video import VideoRecorder
from simmer.ui.window import Window, render_scene, run_window

__all__ = [
    "Bridge",
    "OffscreenRenderer",
    "PygameRenderer",
    "RecordingRenderer",
    "Renderer",
    "ScenePainter",
    "VideoRecorder",
    "View",
    "Window",
    "render_scene",
    "run_window",
]
