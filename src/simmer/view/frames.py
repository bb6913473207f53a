"""When a video's frames are due and which video files can be written: pygame-free, so a
replay's timeline (:mod:`simmer.view.replay_model`) and the command line's checks share them
with the video recorder (:mod:`simmer.ui.video`) without importing pygame."""

from __future__ import annotations

import math
from pathlib import Path

from simmer.world.events import Event, ResetEvent, StepEvent

FPS = 30
"""Frames per simulated second, unless told otherwise."""
VIDEO_SUFFIXES = (".mp4", ".gif")
MAX_FPS = 240
"""More frames a second than steps only repeat frames (60 steps a second by default)."""
GIF_MAX_FPS = 50
"""GIF delays are whole centiseconds and viewers slow down delays under 2 cs."""
EPSILON = 1e-9


def check_video_path(path: str | Path, fps: int = FPS) -> Path:
    """``path`` as a :class:`Path` if it names a video :mod:`simmer.ui.video` writes at
    ``fps`` frames a second; ValueError saying why not."""
    path = Path(path)
    suffix = path.suffix.lower()
    if suffix not in VIDEO_SUFFIXES:
        raise ValueError(f"a video file ends in .mp4 or .gif, not {path.name!r}")
    limit = GIF_MAX_FPS if suffix == ".gif" else MAX_FPS
    if not 1 <= fps <= limit:
        raise ValueError(f"frames per second must be 1 to {limit} for {suffix}, not {fps}")
    return path


class FrameClock:
    """When frames are due: one each ``1 / fps`` simulated seconds from ``start``, the first at
    ``start`` itself, going on across resets (the simulation's clock restarts, the video's
    does not)."""

    def __init__(self, fps: int, start: float) -> None:
        self.fps = fps
        self.frames = 0
        """Frames due so far."""
        self._start = start
        self._offset = 0.0  # simulated seconds before the last reset

    def due(self, event: Event) -> int:
        """How many more frames are due after ``event`` (a step may reach several frame times
        when frames are more frequent than steps); counts them as done."""
        if isinstance(event, ResetEvent):
            self._offset += event.time
        if not isinstance(event, StepEvent):
            return 0
        elapsed = self._offset + event.time - self._start
        count = max(0, math.floor(elapsed * self.fps + EPSILON) + 1 - self.frames)
        self.frames += count
        return count
