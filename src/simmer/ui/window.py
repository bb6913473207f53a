"""The window: one :meth:`Window.frame` per drawn frame reads the events, draws and flips.

A :class:`~simmer.runner.Runner` calls :meth:`Window.frame` as its ``on_frame`` hook; tests call
it directly (posting pygame events and stepping the simulation themselves).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Protocol

import pygame

from simmer.errors import SimmerError
from simmer.geometry import FloatArray, Pose, point_in_polygon
from simmer.ui.hud import CommandLog, Stopwatch, paint_help, paint_hud, paint_hud_static
from simmer.ui.render import PygameRenderer, TextCache, merge_rects
from simmer.ui.scene import ScenePainter, View, default_window_size
from simmer.world import Simulation

if TYPE_CHECKING:
    from simmer.runner import Runner

SPEEDS = (0.125, 0.25, 0.5, 1.0, 2.0, 4.0, 8.0, 16.0, 32.0)
"""The speed factors ``+`` and ``-`` step through."""
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


class Controls(Protocol):
    """What the window asks of the loop that steps the simulation (the Runner has these)."""

    paused: bool
    speed: float | None

    def step_once(self) -> None:
        """Advance one step."""
        ...


@dataclass
class LocalControls:
    """Pause and speed state when no runner drives the window (tests, :func:`run_window`)."""

    sim: Simulation
    paused: bool = False
    speed: float | None = 1.0

    def step_once(self) -> None:
        """Advance one step."""
        self.sim.step()


@dataclass
class Drag:
    """A mouse drag of the robot: which button, where it began, the robot's pose then."""

    button: int
    start: tuple[float, float]
    pose: Pose


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


class Window:
    """Draws a simulation and turns keys and mouse into actions on it.

    ``surface``: draw there instead of opening a window (off-screen rendering, benchmarks).
    """

    def __init__(
        self,
        sim: Simulation,
        *,
        size: tuple[int, int] | None = None,
        surface: pygame.Surface | None = None,
    ) -> None:
        self.sim = sim
        pygame.display.init()
        self.text = TextCache()
        self._own_display = surface is None
        if surface is None:
            pygame.display.set_caption(f"SimMeR - {sim.config.source}")
            surface = pygame.display.set_mode(size or default_window_size(sim), pygame.RESIZABLE)
        self.screen = surface
        self.renderer = PygameRenderer(surface, self.text)
        self.painter = ScenePainter(sim)
        self.local = LocalControls(sim)
        self.stopwatch = Stopwatch(sim)
        self.commands = CommandLog()
        sim.add_observer(self.stopwatch)
        sim.add_observer(self.commands)
        self.held: set[str] = set()
        self.show_help = False
        self.drag: Drag | None = None
        self.ghost: FloatArray | None = None
        self.static = pygame.Surface((1, 1))
        self.view = View(1.0, 0.0, 0.0)
        self._drawn: list[pygame.Rect] = []  # what the last frame drew over the static layer
        self._updated: list[pygame.Rect] | None = None  # to show on screen; None: everything
        self.layout()

    # ----------------------------------------------------------------- layout

    def layout(self) -> None:
        """Fit the scene to the current surface size and repaint the cached static layer."""
        size = self.screen.get_size()
        self.view = View.fit(self.sim, size)
        self.static = static_layer(size, self.screen)
        static = PygameRenderer(self.static, self.text)
        self.painter.paint_static(static, self.view, size)
        paint_hud_static(static, self.sim, size[0])
        self._drawn = [self.static.get_rect()]

    # ----------------------------------------------------------------- the frame hook

    def frame(self, controls: Controls | None = None) -> bool:
        """Handle pending events, draw and show one frame; False when the user quits.

        ``controls`` is the runner (its ``on_frame`` hook passes itself); None uses the
        window's own :attr:`local` controls.
        """
        ctl = controls if controls is not None else self.local
        for event in pygame.event.get():
            if not self.handle(event, ctl):
                return False
        self.draw(ctl)
        if self._own_display:
            pygame.display.update(self._updated)
        return True

    def draw(self, controls: Controls | None = None) -> None:
        """Draw the frame on the surface (no flip).

        Only what the previous frame drew is restored from the cached static layer, so a frame
        costs the size of the robot, rays and HUD values, not of the window.
        """
        ctl = controls if controls is not None else self.local
        screen = self.screen
        static = self.static
        previous = self._drawn
        everything = previous == [static.get_rect()]
        if everything:
            screen.blit(static, (0, 0))
        else:
            for rect in previous:
                screen.blit(static, rect, rect)
        r = self.renderer
        r.dirty.clear()
        self.painter.paint_dynamic(r, self.view, self.ghost)
        clients = getattr(ctl, "clients", None)
        paint_hud(
            r,
            self.sim,
            held=self.held,
            paused=ctl.paused,
            speed=ctl.speed,
            stopwatch=self.stopwatch,
            commands=self.commands.entries,
            clients=list(clients) if clients is not None else None,
        )
        if self.show_help:
            paint_help(r, screen.get_size())
        self._drawn = merge_rects(r.dirty)
        self._updated = None if everything else previous + self._drawn

    # ----------------------------------------------------------------- events

    def handle(self, event: pygame.event.Event, controls: Controls) -> bool:
        """Act on one pygame event; False means quit."""
        kind = event.type
        if kind == pygame.QUIT:
            return False
        if kind == pygame.KEYDOWN:
            return self._key_down(event, controls)
        if kind == pygame.KEYUP and event.key in DRIVE_KEYS:
            self.held.discard(DRIVE_KEYS[event.key])
            self.sim.set_manual_keys(self.held)
        elif kind == pygame.WINDOWFOCUSLOST and self.held:
            self.held.clear()
            self.sim.set_manual_keys(self.held)
        elif kind == pygame.WINDOWEXPOSED:
            self._drawn = [self.static.get_rect()]  # redraw and show the whole window
        elif kind == pygame.VIDEORESIZE and self._own_display:
            self.screen = pygame.display.get_surface() or self.screen
            self.renderer.surface = self.screen
            self.layout()
        elif kind == pygame.MOUSEBUTTONDOWN and event.button in (1, 3):
            self._drag_start(event.pos, event.button)
        elif kind == pygame.MOUSEMOTION and self.drag is not None:
            self._drag_to(event.pos)
        elif kind == pygame.MOUSEBUTTONUP and self.drag is not None:
            self._drag_to(event.pos)
            if self.sim.robot.pose != self.drag.pose:
                self.stopwatch.reset()
            self.drag = None
            self.ghost = None
        return True

    def _key_down(self, event: pygame.event.Event, controls: Controls) -> bool:
        key = event.key
        char = getattr(event, "unicode", "")
        if key == pygame.K_ESCAPE:
            return False
        if key in DRIVE_KEYS:
            self.held.add(DRIVE_KEYS[key])
            self.sim.set_manual_keys(self.held)
        elif key == pygame.K_SPACE:
            controls.paused = not controls.paused
        elif key in STEP_KEYS and controls.paused:
            controls.step_once()
        elif key in FASTER_KEYS or char == "+":
            controls.speed = faster(controls.speed)
        elif key in SLOWER_KEYS or char == "-":
            controls.speed = slower(controls.speed)
        elif key == pygame.K_r:
            self.reset()
        elif key == pygame.K_h:
            self.show_help = not self.show_help
        return True

    def reset(self) -> None:
        """Robot, block, devices, time and stopwatch back to the start; drive keys released."""
        self.held.clear()
        self.drag = None
        self.ghost = None
        self.sim.reset()
        self.stopwatch.reset()

    # ----------------------------------------------------------------- mouse

    def _drag_start(self, pos: tuple[int, int], button: int) -> None:
        x, y = self.view.to_world(*pos)
        robot = self.sim.robot
        if point_in_polygon(x, y, robot.polygon()):
            self.drag = Drag(button, (x, y), robot.pose)

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
        if self.sim.place_robot(*target):
            self.ghost = None
        else:
            self.ghost = self.sim.robot.polygon(target)

    # ----------------------------------------------------------------- lifecycle

    def close(self) -> None:
        """Stop observing the simulation and close the window."""
        for observer in (self.stopwatch, self.commands):
            if observer in self.sim.observers:
                self.sim.observers.remove(observer)
        if self._own_display:
            pygame.display.quit()


def static_layer(size: tuple[int, int], like: pygame.Surface) -> pygame.Surface:
    """A surface for the cached static layer, in ``like``'s pixel format.

    It is a subsurface one pixel into a slightly wider surface: when source and destination
    rows start at the same offset within a memory page, SDL's row copies run into 4K aliasing
    and restoring a rectangle costs up to 20 times more (measured: a 33 × 64 px restore took
    23 µs instead of 0.5 µs; a full-window copy 364 µs instead of 154 µs).
    """
    parent = pygame.Surface((size[0] + 1, size[1]), 0, like)
    return parent.subsurface((1, 0, size[0], size[1]))


def render_scene(sim: Simulation, path: str | Path | None = None) -> pygame.Surface:
    """Draw one frame off-screen at the default size; save it as an image if ``path`` is given."""
    pygame.display.init()
    surface = pygame.Surface(default_window_size(sim))
    window = Window(sim, surface=surface)
    window.draw()
    window.close()
    if path is not None:
        pygame.image.save(surface, str(path))
    return surface


def run_window(runner: Runner, until: float | None = None) -> None:
    """Open a window on the runner's simulation; run until the user quits (or simulated
    ``until`` seconds).

    Raises :class:`~simmer.errors.SimmerError` if no window can be opened (no display).
    """
    try:
        window = Window(runner.sim)
    except pygame.error as exc:
        raise SimmerError(f"cannot open a window ({exc}); use --headless") from None
    try:
        runner.run(on_frame=window.frame, until=until)
    except KeyboardInterrupt:  # Ctrl-C in the terminal: close quietly, like Esc
        pass
    finally:
        window.close()
