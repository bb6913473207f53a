"""The window: pygame in the main thread, the simulation in its own thread.

Drawing never starves the control link. :meth:`Window.run` starts the simulation thread, which
runs :meth:`Runner.run <simmer.runner.Runner.run>` (stepping, and answering every transport the
moment a message arrives) with :meth:`Bridge.sync <simmer.ui.bridge.Bridge.sync>` as its
``on_frame`` hook, and keeps pygame in the calling (main) thread, as macOS requires. Each
:meth:`Window.frame` reads the events and turns them into actions posted to the bridge (it never
calls the :class:`~simmer.world.Simulation`), draws the latest
:class:`~simmer.view.snapshot.Snapshot` and flips, however long the flip blocks (vsync, a slow X
server). Esc, closing the window or Ctrl-C stops and joins the simulation thread.

Tests drive both sides in one thread for determinism: post events, :meth:`Window.frame`,
``bridge.sync()``, step the simulation.
"""

from __future__ import annotations

import logging
import math
import os
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

import pygame

from simmer.errors import SimmerError
from simmer.geometry import Pose, point_in_polygon
from simmer.record.safefile import replacing
from simmer.ui.bridge import (
    SPEEDS,
    Bridge,
    ChangeSpeed,
    Controls,
    EndDrag,
    HoldKeys,
    LocalControls,
    Notice,
    PlaceRobot,
    Quit,
    Reset,
    StepOnce,
    TogglePause,
    ToggleVideo,
    faster,
    slower,
)
from simmer.ui.offscreen import OffscreenRenderer
from simmer.ui.scene import ScenePainter, View, default_window_size
from simmer.untrusted import drawable
from simmer.view.snapshot import Snapshot
from simmer.world import Simulation

if TYPE_CHECKING:
    from simmer.runner import Runner

__all__ = [
    "SPEEDS",
    "Controls",
    "Drag",
    "LocalControls",
    "Window",
    "faster",
    "new_file",
    "render_scene",
    "run_window",
    "save_screenshot",
    "slower",
]

log = logging.getLogger("simmer.ui")

HIDDEN_DRIVERS = ("offscreen", "dummy")
"""SDL video drivers that draw nowhere visible (no display on this machine)."""
DISPLAY_RATE = 60.0
"""Frames per second at which the window reads events when no new snapshot arrives."""
JOIN_TIMEOUT = 10.0
"""Seconds to wait for the simulation thread to stop before giving up on it."""
DRIVE_KEYS = {
    pygame.K_w: "w",
    pygame.K_a: "a",
    pygame.K_s: "s",
    pygame.K_d: "d",
    pygame.K_q: "q",
    pygame.K_e: "e",
}
FASTER_KEYS = (pygame.K_PLUS, pygame.K_EQUALS, pygame.K_KP_PLUS)
SLOWER_KEYS = (pygame.K_MINUS, pygame.K_KP_MINUS)
STEP_KEYS = (pygame.K_PERIOD, pygame.K_KP_PERIOD)


@dataclass(frozen=True)
class Drag:
    """A mouse drag of the robot: which button, where it began, the robot's pose then."""

    button: int
    start: tuple[float, float]
    pose: Pose


class Window:
    """Draws a bridge's snapshots and turns keys and mouse into actions posted to it.

    ``surface``: draw there instead of opening a window (off-screen rendering, benchmarks).
    ``save_dir``: where V records videos and P saves screenshots (default: the current folder).
    """

    def __init__(
        self,
        bridge: Bridge,
        *,
        size: tuple[int, int] | None = None,
        surface: pygame.Surface | None = None,
        save_dir: Path | None = None,
    ) -> None:
        self.bridge = bridge
        self.save_dir = save_dir
        self.scene = bridge.scene
        pygame.display.init()  # the event queue, even when drawing on a given surface
        self._own_display = surface is None
        if surface is None:
            pygame.display.set_caption(drawable(f"SimMeR - {self.scene.config.source}"))
            surface = pygame.display.set_mode(
                size or default_window_size(self.scene), pygame.RESIZABLE
            )
        self.screen = surface
        self.canvas = OffscreenRenderer(self.scene, surface)
        """Draws the snapshots on :attr:`screen`: the same code as the video's frames."""
        self.held: set[str] = set()
        self.show_help = False
        self.drag: Drag | None = None
        self._updated: list[pygame.Rect] | None = None  # to show on screen; None: everything
        self._shown: Snapshot | None = None  # the snapshot on screen, if nothing else changed

    @property
    def view(self) -> View:
        """Where the maze sits on the screen."""
        return self.canvas.view

    @property
    def painter(self) -> ScenePainter:
        """The scene painter."""
        return self.canvas.painter

    # ----------------------------------------------------------------- one frame

    def frame(self) -> bool:
        """Handle pending events, draw the latest snapshot and show it; False when the user
        quits. Skips drawing and flipping if neither the snapshot nor the window changed."""
        for event in pygame.event.get():
            if not self.handle(event):
                self.bridge.post(Quit())
                return False
        snap = self.bridge.latest
        if snap is self._shown:
            return True
        self.draw(snap)
        if self._own_display:
            pygame.display.update(self._updated)
        return True

    def draw(self, snap: Snapshot | None = None) -> None:
        """Draw a snapshot (default: the bridge's latest) on the surface, without a flip
        (:meth:`OffscreenRenderer.draw <simmer.ui.offscreen.OffscreenRenderer.draw>`)."""
        if snap is None:
            snap = self.bridge.latest
        self._updated = self.canvas.draw(snap, show_help=self.show_help)
        self._shown = snap

    # ----------------------------------------------------------------- events

    def handle(self, event: pygame.event.Event) -> bool:
        """Act on one pygame event (posting actions to the bridge); False means quit."""
        kind = event.type
        self._shown = None  # whatever it was, draw the next frame
        if kind == pygame.QUIT:
            return False
        if kind == pygame.KEYDOWN:
            return self._key_down(event)
        if kind == pygame.KEYUP and event.key in DRIVE_KEYS:
            self.held.discard(DRIVE_KEYS[event.key])
            self.bridge.post(HoldKeys(frozenset(self.held)))
        elif kind == pygame.WINDOWFOCUSLOST and self.held:
            self.held.clear()
            self.bridge.post(HoldKeys(frozenset()))
        elif kind == pygame.WINDOWEXPOSED:
            self.canvas.invalidate()  # redraw and show the whole window
        elif kind == pygame.VIDEORESIZE and self._own_display:
            self.screen = pygame.display.get_surface() or self.screen
            self.canvas.use(self.screen)
        elif kind == pygame.MOUSEBUTTONDOWN and event.button in (1, 3):
            self._drag_start(event.pos, event.button)
        elif kind == pygame.MOUSEMOTION and self.drag is not None:
            self._drag_to(event.pos)
        elif kind == pygame.MOUSEBUTTONUP and self.drag is not None:
            self._drag_to(event.pos)
            self.bridge.post(EndDrag())
            self.drag = None
        return True

    def _key_down(self, event: pygame.event.Event) -> bool:
        key = event.key
        char = getattr(event, "unicode", "")
        post = self.bridge.post
        if key == pygame.K_ESCAPE:
            return False
        if key in DRIVE_KEYS:
            self.held.add(DRIVE_KEYS[key])
            post(HoldKeys(frozenset(self.held)))
        elif key == pygame.K_SPACE:
            post(TogglePause())
        elif key in STEP_KEYS:
            post(StepOnce())  # only steps while paused
        elif key in FASTER_KEYS or char == "+":
            post(ChangeSpeed(faster=True))
        elif key in SLOWER_KEYS or char == "-":
            post(ChangeSpeed(faster=False))
        elif key == pygame.K_r:
            self.reset()
        elif key == pygame.K_h:
            self.show_help = not self.show_help
        elif key == pygame.K_t:
            self.canvas.show_trail = not self.canvas.show_trail
        elif key == pygame.K_b:
            self.canvas.show_belief = not self.canvas.show_belief
        elif key == pygame.K_v:
            # the path is used only if no video is being recorded
            post(ToggleVideo(new_file(self.save_dir, ".mp4")))
        elif key == pygame.K_p:
            post(Notice(f"saved the screenshot {self.screenshot()}"))
        return True

    def screenshot(self) -> Path:
        """Save what the window shows as a PNG in :attr:`save_dir`; its path."""
        return save_screenshot(self.screen, new_file(self.save_dir, ".png"))

    def reset(self) -> None:
        """Ask for robot, block, devices, time and outcome back at the start; keys released."""
        self.held.clear()
        self.drag = None
        self.bridge.post(Reset())

    # ----------------------------------------------------------------- mouse

    def _drag_start(self, pos: tuple[int, int], button: int) -> None:
        x, y = self.view.to_world(*pos)
        snap = self.bridge.latest
        if point_in_polygon(x, y, snap.outline):
            self.drag = Drag(button, (x, y), snap.pose)

    def _drag_to(self, pos: tuple[int, int]) -> None:
        drag = self.drag
        assert drag is not None
        x, y = self.view.to_world(*pos)
        start = drag.pose
        if drag.button == 1:
            target = Pose(start.x + x - drag.start[0], start.y + y - drag.start[1], start.heading)
        else:
            before = math.atan2(drag.start[1] - start.y, drag.start[0] - start.x)
            now = math.atan2(y - start.y, x - start.x)
            target = Pose(start.x, start.y, start.heading + math.degrees(now - before))
        self.bridge.post(PlaceRobot(target))

    # ----------------------------------------------------------------- the two threads

    def run(
        self,
        runner: Runner,
        *,
        until: float | None = None,
        stop: threading.Event | None = None,
    ) -> None:
        """Step and serve ``runner`` in a simulation thread; draw here until the user quits,
        ``stop`` is set, or the runner reaches simulated ``until`` seconds.

        ``runner.sim`` must be the bridge's simulation. Ctrl-C (KeyboardInterrupt in this
        thread) quits like Esc. An exception in the simulation thread is raised here.
        """
        if runner.sim is not self.bridge.sim:
            raise ValueError("the runner steps another simulation than the window's bridge")
        stop = stop if stop is not None else threading.Event()
        failure: list[BaseException] = []

        def simulate() -> None:
            try:
                runner.run(on_frame=self.bridge.sync, stop_event=stop, until=until)
                self.bridge.sync(runner)  # the final state, for whoever looks after the run
            except BaseException as exc:  # re-raised in the window thread
                failure.append(exc)
            finally:
                stop.set()

        thread = threading.Thread(target=simulate, name="simmer-simulation", daemon=True)
        thread.start()
        bridge = self.bridge
        try:
            while not stop.is_set():
                bridge.forget()
                if not self.frame():
                    break
                # Draw each snapshot as it comes (the runner publishes at most 60 a second; a
                # vsynced flip paces this loop too); read the events at least that often.
                bridge.wait(1.0 / DISPLAY_RATE)
        except KeyboardInterrupt:  # Ctrl-C in the terminal: close quietly, like Esc
            pass
        finally:
            stop.set()
            thread.join(JOIN_TIMEOUT)
        if failure:
            raise failure[0]

    # ----------------------------------------------------------------- lifecycle

    def close(self) -> None:
        """Close the window (the bridge is closed by whoever made it)."""
        if self._own_display:
            pygame.display.quit()


def new_file(folder: Path | None, suffix: str) -> Path:
    """``simmer-<date>-<time><suffix>`` in ``folder`` (None: the current folder), numbered if
    taken."""
    folder = folder if folder is not None else Path.cwd()
    stem = time.strftime("simmer-%Y%m%d-%H%M%S")
    path = folder / f"{stem}{suffix}"
    number = 1
    while os.path.lexists(path):  # a link pointing nowhere is taken too
        number += 1
        path = folder / f"{stem}-{number}{suffix}"
    return path


def save_screenshot(surface: pygame.Surface, path: Path) -> Path:
    """Save ``surface`` as an image at ``path`` (and say so in the log), never through a link
    there (:class:`~simmer.errors.UnsafeOutput`); ``path``."""
    with replacing(path, run_folder=False) as temp:
        pygame.image.save(surface, str(temp))
    log.info("saved a screenshot: %s", path)
    return path


def render_scene(sim: Simulation, path: str | Path | None = None) -> pygame.Surface:
    """Draw one frame off-screen at the default size (no display needed); save it as an image
    if ``path`` is given."""
    bridge = Bridge(sim)
    canvas = OffscreenRenderer(bridge.scene)
    canvas.draw(bridge.latest)
    bridge.close()
    if path is not None:
        pygame.image.save(canvas.surface, str(path))
    return canvas.surface


def run_window(
    runner: Runner,
    until: float | None = None,
    stop: threading.Event | None = None,
    echo: Callable[[str], None] | None = None,
) -> None:
    """Open a window on the runner's simulation; run until the user quits, ``stop`` is set, or
    simulated ``until`` seconds (see :meth:`Window.run`).

    Once it is open, ``echo`` hears "window open" if the window can be seen; if it cannot (no
    screen), the log says so instead: one message, the true one.
    Raises :class:`~simmer.errors.SimmerError` if no window can be opened (no display).
    """
    bridge = Bridge(runner.sim, echo=echo)
    try:
        window = Window(bridge)
    except pygame.error as exc:
        bridge.close()
        raise SimmerError(f"cannot open a window ({exc}); use --headless") from None
    driver = pygame.display.get_driver()
    if driver in HIDDEN_DRIVERS:
        log.warning(
            "no screen found (SDL video driver %r): the simulator runs and serves, but the "
            "window cannot be seen; use --headless to skip drawing",
            driver,
        )
    elif echo is not None:
        echo("window open (press h for help)")
    try:
        window.run(runner, until=until, stop=stop)
    finally:
        window.close()
        bridge.close()
