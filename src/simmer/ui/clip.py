"""A clip of a recorded run (``simmer render DIR --from T1 --to T2 -o clip.mp4``).

The frames of a :class:`~simmer.view.replay_model.Recording` between two times, drawn off-screen
by the window's own :class:`~simmer.ui.offscreen.OffscreenRenderer` (trail included) at the
window's size rounded down to even numbers, and encoded one by one as they are drawn by the
video's writers (:func:`simmer.ui.video.open_writer`): H.264 MP4 or GIF, :data:`FPS` frames a
simulated second, so the clip plays at real speed.
"""

from __future__ import annotations

from pathlib import Path
from typing import Protocol

import pygame

from simmer.errors import ReplayError, UnsafeOutput
from simmer.ui.offscreen import OffscreenRenderer, even_size
from simmer.ui.scene import default_window_size
from simmer.ui.video import open_writer
from simmer.view.frames import check_video_path
from simmer.view.replay_model import Recording, Timeline

__all__ = ["HasTimeline", "clip_frames", "write_clip"]


class HasTimeline(Protocol):
    """A recording, or runs side by side (:class:`~simmer.view.compare.Comparison`)."""

    @property
    def timeline(self) -> Timeline:
        """Where its frames are in time."""
        ...


def clip_frames(recording: HasTimeline, start: float | None, end: float | None) -> range:
    """The frames from ``start`` up to ``end`` (seconds from the start of the recording; None:
    its start, its end): ``fps * (end - start)`` of them. :class:`ReplayError` if the times
    are not within the run or ``end`` is not after ``start``."""
    timeline = recording.timeline
    duration = timeline.duration
    half_frame = 0.5 / timeline.fps
    within = f"within the run (0 to {duration:.2f} s)"
    if start is not None and not 0 <= start < duration:
        raise ReplayError(f"--from {start:g} s is not {within}")
    if end is not None and not 0 < end <= duration + half_frame:
        raise ReplayError(f"--to {end:g} s is not {within}")
    if start is not None and end is not None and end <= start:
        raise ReplayError(f"--to {end:g} s must be after --from {start:g} s")
    first = 0 if start is None else round(start * timeline.fps)
    stop = timeline.frames if end is None else min(timeline.frames, round(end * timeline.fps))
    return range(first, max(first + 1, stop))


def write_clip(
    recording: Recording,
    path: str | Path,
    start: float | None = None,
    end: float | None = None,
    *,
    run_folder: bool = True,
) -> int:
    """Write the clip from ``start`` to ``end`` (:func:`clip_frames`) into ``path`` (.mp4 or
    .gif); return the number of frames. :class:`ReplayError` for times or a file that will not
    do (a link or no regular file at its name; with ``run_folder``, its folder a link: it is
    in a folder someone else made); what the encoder raises, if it fails."""
    frames = clip_frames(recording, start, end)
    fps = recording.timeline.fps
    try:
        path = check_video_path(path, fps)
    except ValueError as exc:
        raise ReplayError(str(exc)) from None
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        reason = exc.strerror or exc
        raise ReplayError(f"cannot write {path}: no folder {path.parent} ({reason})") from None
    scene = recording.scene
    size = even_size(default_window_size(scene))
    canvas = OffscreenRenderer(scene, pygame.Surface(size, 0, 32))
    try:
        writer = open_writer(path, size, fps, scene, run_folder=run_folder)
    except UnsafeOutput as exc:
        raise ReplayError(str(exc)) from None
    except OSError as exc:
        raise ReplayError(f"cannot write {path}: {exc.strerror or exc}") from None
    try:
        for index in frames:
            changed = canvas.draw(recording.snapshot(index))
            writer.write(canvas.surface, changed)
    finally:
        writer.close()
    return len(frames)
