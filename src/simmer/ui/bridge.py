"""The hand-over between the window thread and the simulation thread.

The window never calls the :class:`~simmer.world.Simulation` (DESIGN habit 3). It :meth:`posts
<Bridge.post>` small immutable actions (keys held, reset, pause, step, speed, place the robot,
quit) on a queue; the thread that owns the simulation calls :meth:`Bridge.sync` between steps
(it is the :class:`~simmer.runner.Runner`'s ``on_frame`` hook, at most ~60 times a second), which
applies them and publishes a fresh :class:`~simmer.view.snapshot.Snapshot` by one reference
assignment to :attr:`Bridge.latest`. Nothing mutable is shared: the queue is thread-safe, the
snapshot never changes.

Tests can run both sides in one thread (post, ``sync``, draw) for determinism.
"""

from __future__ import annotations

import logging
import queue
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

from simmer.geometry import FloatArray, Pose
from simmer.ui.video import VideoRecorder
from simmer.view.maker import Controls, LocalControls, SnapshotMaker
from simmer.view.snapshot import Snapshot, StaticScene, frozen_array
from simmer.world import Simulation

__all__ = [
    "SPEEDS",
    "Action",
    "Bridge",
    "ChangeSpeed",
    "Controls",
    "EndDrag",
    "HoldKeys",
    "LocalControls",
    "PlaceRobot",
    "Quit",
    "Reset",
    "StepOnce",
    "TogglePause",
    "ToggleVideo",
    "faster",
    "slower",
]

log = logging.getLogger("simmer.ui")

SPEEDS = (0.125, 0.25, 0.5, 1.0, 2.0, 4.0, 8.0, 16.0, 32.0)
"""The speed factors ``+`` and ``-`` step through."""


def faster(speed: float | None) -> float | None:
    """The next speed up (``None``, as fast as possible, stays)."""
    if speed is None:
        return None
    return next((s for s in SPEEDS if s > speed * 1.001), SPEEDS[-1])


def slower(speed: float | None) -> float:
    """The next speed down."""
    if speed is None:
        return SPEEDS[-1]
    return next((s for s in reversed(SPEEDS) if s < speed * 0.999), SPEEDS[0])


# ----------------------------------------------------------------- actions


@dataclass(frozen=True)
class HoldKeys:
    """Drive by hand with exactly these keys held (subset of ``wasdqe``)."""

    keys: frozenset[str]


@dataclass(frozen=True)
class Reset:
    """Robot, block, devices, time and the run's outcome back to the start; drive keys
    released."""


@dataclass(frozen=True)
class TogglePause:
    """Pause, or resume."""


@dataclass(frozen=True)
class StepOnce:
    """One step, if paused."""


@dataclass(frozen=True)
class ChangeSpeed:
    """One speed factor up (``faster``) or down."""

    faster: bool


@dataclass(frozen=True)
class PlaceRobot:
    """Move the robot there if it fits (the Task 2 stopwatch then starts again at the next
    motion); if not, the snapshot shows a ghost outline there."""

    pose: Pose


@dataclass(frozen=True)
class EndDrag:
    """A drag ended: clear the ghost outline."""


@dataclass(frozen=True)
class ToggleVideo:
    """Start recording a video into ``path`` (``.mp4`` or ``.gif``), or stop the recording
    going on."""

    path: Path


@dataclass(frozen=True)
class Notice:
    """Show this in the HUD for :data:`NOTICE_SECONDS` (the window saved a screenshot)."""

    text: str


@dataclass(frozen=True)
class Quit:
    """Stop the simulation loop."""


Action = (
    HoldKeys
    | Reset
    | TogglePause
    | StepOnce
    | ChangeSpeed
    | PlaceRobot
    | EndDrag
    | ToggleVideo
    | Notice
    | Quit
)
NOTICE_SECONDS = 8.0
"""Wall-clock seconds a notice stays in the HUD (wall time: it is for the person watching,
and a paused simulation must not keep it forever)."""


class Bridge:
    """Owns the window's view of one simulation: see the module doc.

    Build it in the thread that owns ``sim``, before any other thread starts; after that only
    :meth:`post` and :attr:`latest` may be used from the window thread.
    """

    def __init__(self, sim: Simulation, echo: Callable[[str], None] | None = None) -> None:
        self.sim = sim
        self.echo = echo
        """Where notices are said too (the terminal ``simmer run`` prints to, which a
        ``--program`` run's log file is not): a screenshot's or a video's file."""
        self.scene = StaticScene.of(sim)
        """Configuration and maze: safe to read from any thread."""
        self.local = LocalControls(sim)
        """Pause and speed when :meth:`sync` is called without a runner."""
        self.maker = SnapshotMaker(sim)
        self.outcome = self.maker.outcome
        """The run's outcome the HUD shows (see :attr:`SnapshotMaker.outcome`)."""
        self._actions: queue.SimpleQueue[Action] = queue.SimpleQueue()
        self._ghost: FloatArray | None = None
        self.video: VideoRecorder | None = None
        """The video being recorded from the window (key V), if one is."""
        self._fresh = threading.Event()
        self._notice: tuple[str, float] | None = None  # text, monotonic time it goes
        self.latest: Snapshot = self.maker.snapshot(self.local)
        """The newest snapshot (replaced whole, never changed)."""

    # ----------------------------------------------------------------- the window side

    def post(self, action: Action) -> None:
        """Queue an action for the simulation thread (any thread; never blocks)."""
        self._actions.put(action)

    def forget(self) -> None:
        """Mark the current snapshot as seen: :meth:`wait` then waits for a newer one."""
        self._fresh.clear()

    def wait(self, timeout: float) -> bool:
        """Wait up to ``timeout`` s for a snapshot newer than the last :meth:`forget`."""
        return self._fresh.wait(timeout)

    # ----------------------------------------------------------------- the simulation side

    def sync(self, controls: Controls | None = None) -> bool:
        """Apply the queued actions, publish a snapshot; False if the window asked to quit.

        Called by the thread that owns the simulation (the Runner's ``on_frame`` hook passes
        itself as ``controls``; None uses :attr:`local`).
        """
        ctl = controls if controls is not None else self.local
        keep_running = True
        while True:
            try:
                action = self._actions.get_nowait()
            except queue.Empty:
                break
            if isinstance(action, Quit):
                keep_running = False
            else:
                self._apply(action, ctl)
        recording = self.video.path.name if self.video is not None else None
        self.latest = self.maker.snapshot(ctl, self._ghost, recording, self._notice_text())
        self._fresh.set()
        return keep_running

    def _apply(self, action: Action, ctl: Controls) -> None:
        sim = self.sim
        if isinstance(action, HoldKeys):
            sim.set_manual_keys(action.keys)
        elif isinstance(action, Reset):
            self._ghost = None
            sim.reset()  # its ResetEvent clears the outcome
        elif isinstance(action, TogglePause):
            ctl.paused = not ctl.paused
        elif isinstance(action, StepOnce):
            if ctl.paused:
                ctl.step_once()
        elif isinstance(action, ChangeSpeed):
            ctl.speed = faster(ctl.speed) if action.faster else slower(ctl.speed)
        elif isinstance(action, PlaceRobot):
            target = action.pose
            if sim.place_robot(*target):
                self._ghost = None
            else:
                self._ghost = frozen_array(sim.robot.polygon(target).copy())
        elif isinstance(action, EndDrag):
            self._ghost = None
        elif isinstance(action, ToggleVideo):
            if self.video is None:
                self._start_video(action.path, ctl)
            else:
                self._stop_video()
        elif isinstance(action, Notice):
            self._say(action.text)

    def _say(self, text: str) -> None:
        """Show ``text`` in the HUD for a while, and say it through :attr:`echo`."""
        self._notice = (text, time.monotonic() + NOTICE_SECONDS)
        if self.echo is not None:
            self.echo(text)

    def _notice_text(self) -> str | None:
        """The HUD's notice: the video being recorded, else the last notice for a while."""
        if self.video is not None:
            return f"recording the video {self.video.path} (V stops it)"
        if self._notice is not None and time.monotonic() < self._notice[1]:
            return self._notice[0]
        return None

    def _start_video(self, path: Path, ctl: Controls) -> None:
        try:
            self.video = VideoRecorder(self.sim, path, controls=ctl)
        except (OSError, ValueError) as exc:
            log.error("cannot record a video into %s: %s", path, exc)
            self._say(f"cannot record a video into {path}: {exc}")
        else:
            log.info("recording a video into %s (V stops it)", path)
            if self.echo is not None:
                self.echo(f"recording a video into {path} (V stops it)")

    def _stop_video(self) -> None:
        video, self.video = self.video, None
        if video is None:
            return
        try:
            video.close()
        except Exception as exc:  # the window goes on
            log.error("the video %s could not be written: %s", video.path, exc)
            self._say(f"the video {video.path} could not be written: {exc}")
        else:
            log.info("saved the video %s (%.2f s)", video.path, video.seconds)
            self._say(f"saved the video {video.path} ({video.seconds:.1f} s)")

    def close(self) -> None:
        """Finish a video being recorded and stop observing the simulation (once its thread
        has stopped)."""
        self._stop_video()
        self.maker.close()
