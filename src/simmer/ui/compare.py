"""Runs side by side in a window or a video (``simmer replay RUN_A RUN_B ...``,
``simmer render RUN_A RUN_B ... -o both.mp4``).

A :class:`~simmer.view.compare.Comparison` drawn by :class:`CompareCanvas`: the maze once
(the window's static layer, :class:`~simmer.ui.scene.ScenePainter`), then each run's path,
block and robot in its colour (:func:`simmer.scene.compared_run_items`, a red cross once it
has collided), a legend above the maze (colour, run, time, collisions, whether it ended) and
one timeline under it with a lane per run (its length, a red tick where it first collided).
The window (:class:`CompareWindow`) and the video (:func:`write_comparison`) draw the same
canvas, so a video's frame is what the window showed.
"""

from __future__ import annotations

from pathlib import Path

import pygame

from simmer.colors import COLLISION_COLOR
from simmer.errors import ReplayError, SimmerError, UnsafeOutput
from simmer.scene import compared_run_items
from simmer.ui.clip import clip_frames
from simmer.ui.hud import BOX, DIM, LIT, TEXT, UNLIT
from simmer.ui.offscreen import even_size, static_layer
from simmer.ui.render import PygameRenderer, Renderer, TextCache
from simmer.ui.replay import FASTER_KEYS, SLOWER_KEYS, TIMELINE_HEIGHT, TimelineBar
from simmer.ui.scene import PANEL_HEIGHT, ScenePainter, View, default_window_size, paint_items
from simmer.ui.video import open_writer
from simmer.ui.window import HIDDEN_DRIVERS, new_file, save_screenshot
from simmer.untrusted import drawable
from simmer.view.compare import ComparedRun, Comparison
from simmer.view.frames import check_video_path
from simmer.view.replay_model import Playhead

__all__ = ["CompareCanvas", "CompareWindow", "compare_size", "run_compare", "write_comparison"]

LEGEND_ROW = 34
"""Pixels between the legend's lines (three to a column above the maze)."""
LEGEND_COLUMN = 520
"""Pixels between the legend's columns."""
DISPLAY_RATE = 60
"""Frames per second the window draws at most."""


def compare_size(comparison: Comparison) -> tuple[int, int]:
    """The canvas's size: the live window's, and the timeline under it (even numbers, so a
    video can be H.264)."""
    width, height = default_window_size(comparison.scene)
    return even_size((width, height + TIMELINE_HEIGHT))


class CompareCanvas:
    """Draws a comparison's frames on ``surface`` (default: a new one of :func:`compare_size`).
    The maze is painted once per size into a cached layer; each frame repaints the rest."""

    def __init__(
        self,
        comparison: Comparison,
        surface: pygame.Surface | None = None,
        text: TextCache | None = None,
    ) -> None:
        self.comparison = comparison
        self.surface = surface if surface is not None else pygame.Surface(compare_size(comparison))
        self.text = text or TextCache()
        self.painter = ScenePainter(comparison.scene)
        self.static = pygame.Surface((1, 1))
        self.view = View(1.0, 0.0, 0.0)
        self.layout()

    def use(self, surface: pygame.Surface) -> None:
        """Draw on another surface from now on (the window was resized)."""
        self.surface = surface
        self.layout()

    def layout(self) -> None:
        """Fit the maze above the timeline and repaint the cached maze layer."""
        width, height = self.surface.get_size()
        maze_size = (width, max(PANEL_HEIGHT + 2, height - TIMELINE_HEIGHT))
        self.view = View.fit(self.comparison.scene, maze_size)
        self.static = static_layer((width, height), self.surface)
        self.painter.paint_static(PygameRenderer(self.static, self.text), self.view, maze_size)

    def draw(self, frame: int, *, playing: bool = False, speed: float = 1.0) -> None:
        """Draw frame ``frame`` of every run, the legend and the timeline."""
        surface = self.surface
        surface.blit(self.static, (0, 0))
        r = PygameRenderer(surface, self.text)
        settings = self.comparison.scene.config.settings
        for run in self.comparison.runs:
            shown = run.frame(frame)
            trail = shown.trail.points if shown.trail is not None else None
            placed = shown.layout.place(shown.pose)[: shown.layout.body + 2]
            collided = run.collisions(frame) > 0
            items = compared_run_items(placed, shown.block, trail, run.color, settings, collided)
            paint_items(r, self.view, items)
        self._legend(r, frame)
        width, height = surface.get_size()
        area = surface.subsurface((0, height - TIMELINE_HEIGHT, width, TIMELINE_HEIGHT))
        self._timeline(PygameRenderer(area, self.text), area.get_size(), frame, playing, speed)

    def _legend(self, r: Renderer, frame: int) -> None:
        """A line per run above the maze: its colour, name, time, collisions, end."""
        for i, run in enumerate(self.comparison.runs):
            x, y = 12 + LEGEND_COLUMN * (i // 3), 8 + LEGEND_ROW * (i % 3)
            r.draw_rect((x, y + 2, 22, 22), run.color)
            r.draw_text(_fit(run.label, 20, 250), (x + 32, y + 3), TEXT, 20)
            _legend_state(r, run, frame, x + 290, y + 3)

    def _timeline(
        self, r: Renderer, size: tuple[int, int], frame: int, playing: bool, speed: float
    ) -> None:
        """The one timeline: play state and time, a lane per run as long as the run, a red
        tick where it first collided, and the playhead."""
        width, height = size
        r.fill(BOX)
        r.draw_segment((0, 0), (width, 0), UNLIT, 2)
        comparison = self.comparison
        timeline = comparison.timeline
        state = "playing" if playing else "paused"
        r.draw_text(f"{state}  x{speed:g}", (12, 8), TEXT if playing else LIT, 22)
        now = timeline.frame_time(frame)
        r.draw_text(f"{now:.2f} / {comparison.duration:.2f} s", (12, 32), TEXT, 18)
        bar = TimelineBar(width, comparison.duration)
        lanes = len(comparison.runs)
        lane = max(3, (height - 16) // lanes)
        top = (height - lane * lanes) // 2
        for i, run in enumerate(comparison.runs):
            y = top + i * lane
            end = bar.x(run.recording.duration)
            r.draw_rect((bar.left, y + 1, end - bar.left, lane - 2), run.color)
            hit = run.first_collision()
            if hit is not None:
                x = bar.x(hit)
                r.draw_rect((x - 2, y, 4, lane), COLLISION_COLOR)
        x = bar.x(now)
        r.draw_segment((x, 4), (x, height - 4), TEXT, 3)


def _legend_state(r: Renderer, run: ComparedRun, frame: int, x: int, y: int) -> None:
    """What a run is at ``frame``: its time, its collisions (red once it collided), and
    whether it reached or delivered, ended, or differs from its recording."""
    shown = run.frame(frame)
    collisions = run.collisions(frame)
    r.draw_text(f"{shown.time:.2f} s", (x, y), TEXT, 18)
    word = f"collided ({collisions})" if collisions else "no collision"
    r.draw_text(word, (x + 70, y), COLLISION_COLOR if collisions else DIM, 18)
    parts = []
    outcome = shown.outcome
    if outcome is not None and outcome.project is not None and outcome.project.delivered_at:
        parts.append("delivered")
    elif outcome is not None and outcome.reached:
        parts.append("reached")
    if run.ended(frame):
        parts.append("ended")
    if not run.recording.check.matches:
        parts.append("differs from its recording")
    r.draw_text(", ".join(parts), (x + 200, y), DIM, 18)


def _fit(text: str, size: int, width: float) -> str:
    """``text`` cut (with "...") to about ``width`` pixels at ``size``."""
    letters = max(4, int(width / (0.5 * size)))
    return text if len(text) <= letters else text[: letters - 3] + "..."


class CompareWindow:
    """Shows a :class:`Comparison` and moves through it: Space plays or pauses, + and -
    change the speed, . and , step a frame, Home and End, the timeline to click or drag, P a
    screenshot, Esc quits. ``surface``: draw there instead of opening a window (tests)."""

    def __init__(
        self,
        comparison: Comparison,
        *,
        surface: pygame.Surface | None = None,
        save_dir: Path | None = None,
    ) -> None:
        self.comparison = comparison
        self.playhead = Playhead(comparison.timeline)
        self.save_dir = save_dir
        pygame.display.init()
        self._own_display = surface is None
        if surface is None:
            names = ", ".join(run.label for run in comparison.runs)
            pygame.display.set_caption(drawable(f"SimMeR replay - {names}"))
            surface = pygame.display.set_mode(compare_size(comparison), pygame.RESIZABLE)
        self.screen = surface
        self.canvas = CompareCanvas(comparison, surface)
        self.dragging = False
        self._shown: tuple[object, ...] | None = None

    def draw(self) -> bool:
        """Draw the frame the playhead points at unless it is shown already; whether it drew."""
        playhead = self.playhead
        state = (playhead.frame, playhead.playing, playhead.speed, self.screen.get_size())
        if state == self._shown:
            return False
        self._shown = state
        self.canvas.draw(playhead.frame, playing=playhead.playing, speed=playhead.speed)
        return True

    def frame(self, seconds: float) -> bool:
        """Handle pending events, move on ``seconds`` of wall-clock time and draw; False when
        the user quits."""
        for event in pygame.event.get():
            if not self.handle(event):
                return False
        if not self.dragging:
            self.playhead.advance(seconds)
        if self.draw() and self._own_display:
            pygame.display.flip()
        return True

    def handle(self, event: pygame.event.Event) -> bool:
        """Act on one pygame event; False means quit."""
        kind = event.type
        if kind == pygame.QUIT:
            return False
        if kind == pygame.KEYDOWN:
            return self._key_down(event)
        height = self.screen.get_height()
        on_timeline = kind in (pygame.MOUSEBUTTONDOWN, pygame.MOUSEBUTTONUP, pygame.MOUSEMOTION)
        if kind == pygame.VIDEORESIZE and self._own_display:
            self.screen = pygame.display.get_surface() or self.screen
            self.canvas.use(self.screen)
            self._shown = None
        elif kind == pygame.WINDOWEXPOSED:
            self._shown = None
        elif on_timeline and kind == pygame.MOUSEBUTTONDOWN and event.button == 1:
            if event.pos[1] >= height - TIMELINE_HEIGHT:
                self.dragging = True
                self.playhead.playing = False
                self._seek_to(event.pos[0])
        elif kind == pygame.MOUSEMOTION and self.dragging:
            self._seek_to(event.pos[0])
        elif kind == pygame.MOUSEBUTTONUP and event.button == 1 and self.dragging:
            self._seek_to(event.pos[0])
            self.dragging = False
        return True

    def _seek_to(self, x: int) -> None:
        self.playhead.seek(TimelineBar(self.screen.get_width(), self.comparison.duration).time(x))

    def _key_down(self, event: pygame.event.Event) -> bool:
        key, char = event.key, getattr(event, "unicode", "")
        playhead = self.playhead
        if key == pygame.K_ESCAPE:
            return False
        if key == pygame.K_SPACE:
            playhead.toggle()
        elif key in FASTER_KEYS or char == "+":
            playhead.faster()
        elif key in SLOWER_KEYS or char == "-":
            playhead.slower()
        elif key in (pygame.K_PERIOD, pygame.K_KP_PERIOD):
            playhead.step(1)
        elif key == pygame.K_COMMA:
            playhead.step(-1)
        elif key == pygame.K_HOME:
            playhead.seek(0.0)
        elif key == pygame.K_END:
            playhead.seek(self.comparison.duration)
        elif key == pygame.K_p:
            save_screenshot(self.screen, new_file(self.save_dir, ".png"))
        return True

    def run(self) -> None:
        """Show the runs until the user quits (Esc, closing the window, Ctrl-C)."""
        clock = pygame.time.Clock()
        clock.tick()
        try:
            while self.frame(clock.tick(DISPLAY_RATE) / 1000):
                pass
        except KeyboardInterrupt:
            pass

    def close(self) -> None:
        """Close the window."""
        if self._own_display:
            pygame.display.quit()


def run_compare(comparison: Comparison) -> None:
    """Open a window on the runs side by side, playing from the start, until the user quits;
    :class:`SimmerError` if no window can be opened or seen."""
    instead = "simmer render RUN_A RUN_B -o both.mp4 makes a video of them"
    try:
        window = CompareWindow(comparison)
    except pygame.error as exc:
        raise SimmerError(f"cannot open a window ({exc}); {instead}") from None
    driver = pygame.display.get_driver()
    if driver in HIDDEN_DRIVERS:
        window.close()
        raise SimmerError(f"no screen found (SDL video driver {driver!r}); {instead}")
    window.playhead.playing = True
    try:
        window.run()
    finally:
        window.close()


def write_comparison(
    comparison: Comparison, path: str | Path, start: float | None = None, end: float | None = None
) -> int:
    """Write the runs side by side from ``start`` to ``end`` into ``path`` (.mp4 or .gif) at
    the recordings' frame rate; the number of frames. :class:`ReplayError` for times or a
    file that will not do."""
    frames = clip_frames(comparison, start, end)
    fps = comparison.timeline.fps
    try:
        path = check_video_path(path, fps)
        path.parent.mkdir(parents=True, exist_ok=True)
    except ValueError as exc:
        raise ReplayError(str(exc)) from None
    except OSError as exc:
        raise ReplayError(f"cannot write {path}: {exc.strerror or exc}") from None
    canvas = CompareCanvas(comparison)
    try:
        writer = open_writer(path, canvas.surface.get_size(), fps, comparison.scene)
    except UnsafeOutput as exc:
        raise ReplayError(str(exc)) from None
    except OSError as exc:
        raise ReplayError(f"cannot write {path}: {exc.strerror or exc}") from None
    try:
        for index in frames:
            canvas.draw(index, playing=True)
            writer.write(canvas.surface, None)
    finally:
        writer.close()
    return len(frames)
