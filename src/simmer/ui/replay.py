"""The replay window: a recorded run played back, with its commands beside it and a timeline.

``simmer replay DIR`` re-simulates the run first (:class:`~simmer.view.replay_model.Recording`,
in this thread, before the window opens), then shows it here: the maze and HUD drawn by the
same :class:`~simmer.ui.offscreen.OffscreenRenderer` as the live window and videos (with the
trail), the command list in a panel on the right with the current command highlighted, and
a timeline along the bottom to click or drag. Everything runs in the main thread; the
window's keys only move the :class:`~simmer.view.replay_model.Playhead`, and drawing picks the
frame it points at, so seeking costs one frame's drawing.
"""

from __future__ import annotations

import math
import textwrap
from collections.abc import Callable
from pathlib import Path

import pygame

from simmer.colors import Color, tint
from simmer.errors import SimmerError
from simmer.ui.hud import ALARM, BOX, DIM, LIT, TEXT, UNLIT, reply_text
from simmer.ui.offscreen import OffscreenRenderer
from simmer.ui.render import PygameRenderer, Renderer, TextCache
from simmer.ui.scene import PANEL_HEIGHT, base_scene_size, default_window_size
from simmer.ui.window import HIDDEN_DRIVERS, new_file, save_screenshot
from simmer.untrusted import drawable
from simmer.view.replay_model import Playhead, Recording, ReplayCommand
from simmer.view.snapshot import HasScene

__all__ = ["REPLAY_HELP", "ReplayWindow", "paint_panel", "paint_timeline", "run_replay"]


PANEL_WIDTH = 440
"""Pixels of the command panel right of the maze."""
TIMELINE_HEIGHT = 56
"""Pixels of the timeline under the maze and panel."""
BAR_LEFT = 200
"""Where the timeline's bar starts (the play state and time are left of it)."""
BAR_MARGIN = 24
"""Pixels right of the bar."""
ROW = 18
"""Pixels per command in the list."""
DISPLAY_RATE = 60
"""Frames per second the window draws at most."""
MAX_FRAME_SECONDS = 0.5
"""Wall-clock seconds one frame moves the playhead on at most (times its speed): a window
that took seconds to appear, or a stalled frame, slows the replay down instead of skipping
it (a short run opened at its end, paused, on a busy machine)."""
COLUMNS = (("time", 12), ("command", 64), ("replies", 174), ("from", 338))
"""The command list's columns: heading and left edge."""
MATCH: Color = (120, 220, 120)
HIGHLIGHT: Color = (50, 75, 75)
REPLAY_HELP = (
    ("Space", "play / pause (at the end: again)"),
    ("+ / -", "faster / slower (x0.25 to x16)"),
    ("Right / Left", "next / previous command"),
    (". / ,", "one frame on / back"),
    ("Home / End", "the start / the end"),
    ("timeline", "click or drag: go to that time"),
    ("T", "show / hide the path driven so far (clips show it)"),
    ("B", "show / hide the program's belief, as it showed it"),
    ("P", "screenshot (simmer-*.png here)"),
    ("H", "show / hide this help"),
    ("Esc", "quit (or close the window)"),
)
FASTER_KEYS = (pygame.K_PLUS, pygame.K_EQUALS, pygame.K_KP_PLUS)
SLOWER_KEYS = (pygame.K_MINUS, pygame.K_KP_MINUS)


def replay_window_size(scene: HasScene) -> tuple[int, int]:
    """The window's size: as wide as the live window, the maze narrower to leave room for the
    panel, and the timeline under it."""
    width = default_window_size(scene)[0]
    base_w, base_h = base_scene_size(scene)
    maze_width = max(200, width - PANEL_WIDTH)
    maze_height = PANEL_HEIGHT + math.ceil(base_h * maze_width / base_w)
    return (maze_width + PANEL_WIDTH, maze_height + TIMELINE_HEIGHT)


def short_client(client: str) -> str:
    """A client's name, short: ``stream 127.0.0.1:50312`` -> ``stream 50312``; "" -> ``python``."""
    kind, _, where = client.partition(" ")
    if not kind:
        return "python"
    tail = where.rsplit(":", 1)[-1] if ":" in where else Path(where).name
    return f"{kind} {tail}".strip()


def _fit(text: str, size: int, width: float) -> str:
    """``text`` cut (with "...") to at most about ``width`` pixels at ``size`` (0.42 em a
    letter: digits are wider than most)."""
    letters = max(4, int(width / (0.42 * size)))
    return text if len(text) <= letters else text[: letters - 3] + "..."


# ----------------------------------------------------------------------------- painting


def _check_lines(recording: Recording, width: int) -> list[tuple[str, Color]]:
    """The re-simulation's verdict, wrapped to the panel, with colours."""
    check = recording.check
    letters = int((width - 24) / (0.38 * 18))
    out: list[tuple[str, Color]] = []
    for i, line in enumerate(check.lines()):
        color = (MATCH if check.matches else ALARM) if i == 0 else TEXT
        out += [(part, color) for part in textwrap.wrap(line, letters)]
    return out


def paint_panel(
    r: Renderer, size: tuple[int, int], recording: Recording, playhead: Playhead
) -> None:
    """The panel right of the maze: the run, whether the re-simulation matches, and the
    commands with the current one highlighted (its list scrolls to keep it in view)."""
    width, height = size
    r.fill(BOX)
    r.draw_segment((0, 0), (0, height), UNLIT, 2)
    name = recording.folder.resolve().name
    r.draw_text(_fit(name, 22, width - 24), (12, 10), TEXT, 22)
    count = len(recording.commands)
    facts = f"seed {recording.seed}, {recording.duration:.2f} s, {count} commands"
    r.draw_text(facts, (12, 34), DIM, 18)
    y = 58
    lines = _check_lines(recording, width)
    box = (8, y, width - 16, 10 + 18 * len(lines))
    r.draw_rect(box, tint(BOX, 0.15))
    r.draw_rect(box, lines[0][1], 1)  # green if it matches, red if not
    for i, (line, color) in enumerate(lines):
        r.draw_text(line, (14, y + 6 + 18 * i), color, 18)
    y += 24 + 18 * len(lines)
    for label, x in COLUMNS:
        r.draw_text(label, (x, y), DIM, 18)
    y += 22
    if not recording.commands:
        r.draw_text("no commands in this run", (12, y), DIM, 18)
        return
    rows = max(1, (height - y - 6) // ROW)
    current = playhead.command
    first = min(max(0, current - rows // 3), max(0, count - rows))
    for index in range(first, min(count, first + rows)):
        _paint_command(r, recording.commands[index], y, width, index == current)
        y += ROW


def _paint_command(r: Renderer, command: ReplayCommand, y: int, width: int, current: bool) -> None:
    """One row of the command list: time, message, replies (red if the recording's differ),
    client."""
    if current:
        r.draw_rect((4, y - 2, width - 8, ROW), HIGHLIGHT)
    color = LIT if current else TEXT
    event = command.event
    replies = ", ".join(reply_text(v) for v in event.replies)
    (_, time_x), (_, message_x), (_, replies_x), (_, client_x) = COLUMNS
    r.draw_text(f"{command.time:.2f}", (time_x, y), color, 18)
    r.draw_text(_fit(event.message, 18, replies_x - message_x - 8), (message_x, y), color, 18)
    replies_color = ALARM if command.differs else color
    r.draw_text(_fit(replies, 18, client_x - replies_x - 8), (replies_x, y), replies_color, 18)
    client = _fit(short_client(event.client), 16, width - client_x - 6)
    r.draw_text(client, (client_x, y + 1), DIM, 16)


class TimelineBar:
    """Where the timeline's bar is in a surface of ``width`` pixels, and time <-> pixel."""

    def __init__(self, width: int, duration: float) -> None:
        self.left = BAR_LEFT
        self.right = max(BAR_LEFT + 10, width - BAR_MARGIN)
        self.duration = duration

    def x(self, time: float) -> float:
        """The pixel column of ``time``."""
        if self.duration <= 0:
            return self.left
        return self.left + (self.right - self.left) * min(1.0, max(0.0, time / self.duration))

    def time(self, x: float) -> float:
        """The time at pixel column ``x`` (clamped to the bar)."""
        fraction = (x - self.left) / (self.right - self.left)
        return self.duration * min(1.0, max(0.0, fraction))


def paint_timeline(
    r: Renderer, size: tuple[int, int], recording: Recording, playhead: Playhead
) -> None:
    """The timeline: play state, speed and time; the bar with a tick per command, the first
    difference from the recording in red, and the playhead."""
    width, height = size
    r.fill(BOX)
    r.draw_segment((0, 0), (width, 0), UNLIT, 2)
    state = "playing" if playhead.playing else "end: Space" if playhead.at_end else "paused"
    r.draw_text(f"{state}  x{playhead.speed:g}", (12, 8), TEXT if playhead.playing else LIT, 22)
    shown = recording.timeline.frame_time(playhead.frame)
    r.draw_text(f"{shown:.2f} / {recording.duration:.2f} s", (12, 32), TEXT, 18)
    bar = TimelineBar(width, recording.duration)
    middle = height // 2 + 2
    r.draw_rect((bar.left, middle - 4, bar.right - bar.left, 8), UNLIT)
    now = bar.x(playhead.time)
    r.draw_rect((bar.left, middle - 4, now - bar.left, 8), tint(LIT, 0.3, BOX))
    columns = sorted({round(bar.x(command.time)) for command in recording.commands})
    for column in columns:
        r.draw_segment((column, middle - 12), (column, middle - 6), DIM, 1)
    difference = recording.check.difference_time
    if difference is not None:
        x = bar.x(difference)
        r.draw_segment((x, 6), (x, height - 6), ALARM, 3)
    r.draw_circle((now, middle), 8, TEXT)
    r.draw_text("h: keys", (bar.right - 50, middle + 8), DIM, 16)


# ----------------------------------------------------------------------------- the window


class ReplayWindow:
    """Shows a :class:`Recording` and moves through it with the keys and the timeline.

    ``surface``: draw there instead of opening a window (tests, screenshots).
    ``save_dir``: where P saves screenshots (default: the current folder).
    """

    def __init__(
        self,
        recording: Recording,
        *,
        size: tuple[int, int] | None = None,
        surface: pygame.Surface | None = None,
        save_dir: Path | None = None,
    ) -> None:
        self.recording = recording
        self.playhead = Playhead(recording.timeline)
        self.save_dir = save_dir
        pygame.display.init()  # the event queue, even when drawing on a given surface
        self._own_display = surface is None
        if surface is None:
            pygame.display.set_caption(drawable(f"SimMeR replay - {recording.folder}"))
            surface = pygame.display.set_mode(
                size or replay_window_size(recording.scene), pygame.RESIZABLE
            )
        self.screen = surface
        self.text = TextCache()
        self.show_help = False
        self.dragging = False
        self._resume = False  # playing when the drag began
        self._shown: tuple[object, ...] | None = None
        self.canvas = OffscreenRenderer(recording.scene, self._area(self.maze_rect), self.text)
        """Draws the maze and HUD: the same code as the live window and the videos."""

    # ----------------------------------------------------------------- layout

    @property
    def maze_rect(self) -> pygame.Rect:
        """Where the maze and HUD are."""
        width, height = self.screen.get_size()
        return pygame.Rect(0, 0, max(2, width - PANEL_WIDTH), max(2, height - TIMELINE_HEIGHT))

    @property
    def panel_rect(self) -> pygame.Rect:
        """Where the command panel is."""
        maze = self.maze_rect
        return pygame.Rect(maze.right, 0, max(0, self.screen.get_width() - maze.right), maze.h)

    @property
    def timeline_rect(self) -> pygame.Rect:
        """Where the timeline is."""
        maze = self.maze_rect
        return pygame.Rect(0, maze.bottom, self.screen.get_width(), TIMELINE_HEIGHT)

    def _area(self, rect: pygame.Rect) -> pygame.Surface:
        return self.screen.subsurface(rect.clip(self.screen.get_rect()))

    # ----------------------------------------------------------------- one frame

    def frame(self, seconds: float) -> bool:
        """Handle pending events, move the playhead on by ``seconds`` of wall-clock time, and
        draw and show the window if anything changed; False when the user quits."""
        for event in pygame.event.get():
            if not self.handle(event):
                return False
        if not self.dragging:
            self.playhead.advance(min(seconds, MAX_FRAME_SECONDS))
        if self.draw() and self._own_display:
            pygame.display.flip()
        return True

    def draw(self) -> bool:
        """Draw the frame the playhead points at, the panel and the timeline, unless they are
        already shown as they are; whether it drew."""
        playhead = self.playhead
        state = (
            playhead.frame,
            playhead.command,
            playhead.playing,
            playhead.speed,
            self.show_help,
            self.canvas.show_trail,
            self.canvas.show_belief,
            self.screen.get_size(),
        )
        if state == self._shown:
            return False
        self._shown = state
        snap = self.recording.snapshot(
            playhead.frame, paused=not playhead.playing, speed=playhead.speed
        )
        self.canvas.draw(snap, show_help=self.show_help, keys=REPLAY_HELP)
        for rect, painter in (
            (self.panel_rect, paint_panel),
            (self.timeline_rect, paint_timeline),
        ):
            if rect.w > 0 and rect.h > 0:
                area = self._area(rect)
                painter(PygameRenderer(area, self.text), area.get_size(), self.recording, playhead)
        return True

    # ----------------------------------------------------------------- events

    def handle(self, event: pygame.event.Event) -> bool:
        """Act on one pygame event; False means quit."""
        kind = event.type
        if kind == pygame.QUIT:
            return False
        if kind == pygame.KEYDOWN:
            return self._key_down(event)
        if kind == pygame.VIDEORESIZE and self._own_display:
            self.screen = pygame.display.get_surface() or self.screen
            self.canvas.use(self._area(self.maze_rect))
            self._shown = None
        elif kind == pygame.WINDOWEXPOSED:
            self.canvas.invalidate()
            self._shown = None
        elif kind == pygame.MOUSEBUTTONDOWN and event.button == 1:
            if self.timeline_rect.collidepoint(event.pos):
                self.dragging = True
                self._resume = self.playhead.playing
                self.playhead.playing = False
                self._seek_to(event.pos[0])
        elif kind == pygame.MOUSEMOTION and self.dragging:
            self._seek_to(event.pos[0])
        elif kind == pygame.MOUSEBUTTONUP and event.button == 1 and self.dragging:
            self._seek_to(event.pos[0])
            self.dragging = False
            self.playhead.playing = self._resume and not self.playhead.at_end
        return True

    def _seek_to(self, x: int) -> None:
        bar = TimelineBar(self.timeline_rect.w, self.recording.duration)
        self.playhead.seek(bar.time(x))

    def _key_down(self, event: pygame.event.Event) -> bool:
        key = event.key
        char = getattr(event, "unicode", "")
        playhead = self.playhead
        if key == pygame.K_ESCAPE:
            return False
        if key == pygame.K_SPACE:
            playhead.toggle()
        elif key in FASTER_KEYS or char == "+":
            playhead.faster()
        elif key in SLOWER_KEYS or char == "-":
            playhead.slower()
        elif key == pygame.K_RIGHT:
            playhead.next_command()
        elif key == pygame.K_LEFT:
            playhead.previous_command()
        elif key in (pygame.K_PERIOD, pygame.K_KP_PERIOD):
            playhead.step(1)
        elif key == pygame.K_COMMA:
            playhead.step(-1)
        elif key == pygame.K_HOME:
            playhead.seek(0.0)
        elif key == pygame.K_END:
            playhead.seek(self.recording.duration)
        elif key == pygame.K_t:
            self.canvas.show_trail = not self.canvas.show_trail
        elif key == pygame.K_b:
            self.canvas.show_belief = not self.canvas.show_belief
        elif key == pygame.K_h:
            self.show_help = not self.show_help
        elif key == pygame.K_p:
            save_screenshot(self.screen, new_file(self.save_dir, ".png"))
        return True

    # ----------------------------------------------------------------- lifecycle

    def run(self) -> None:
        """Show the replay until the user quits (Esc, closing the window, Ctrl-C)."""
        clock = pygame.time.Clock()
        clock.tick()
        try:
            while self.frame(clock.tick(DISPLAY_RATE) / 1000):
                pass
        except KeyboardInterrupt:  # Ctrl-C in the terminal: close quietly, like Esc
            pass

    def close(self) -> None:
        """Close the window."""
        if self._own_display:
            pygame.display.quit()


def run_replay(recording: Recording, echo: Callable[[str], None] | None = None) -> None:
    """Open a window on ``recording``, playing from the start, until the user quits;
    :class:`SimmerError` if no window can be opened or none could be seen (no screen: unlike
    a live run, which still serves, a replay nobody sees does nothing). ``echo`` hears
    "window open" once it is open."""
    instead = (
        "simmer render DIR -o clip.mp4 makes a video of it, and simmer replay --check DIR "
        "compares it with its recording without a window"
    )
    try:
        window = ReplayWindow(recording)
    except pygame.error as exc:
        raise SimmerError(f"cannot open a window ({exc}); {instead}") from None
    driver = pygame.display.get_driver()
    if driver in HIDDEN_DRIVERS:
        window.close()
        raise SimmerError(f"no screen found (SDL video driver {driver!r}); {instead}")
    if echo is not None:
        echo("replay window open, playing from the start (Space: pause, or at the end play "
             "again; h: the keys)")  # fmt: skip
    window.playhead.playing = True
    try:
        window.run()
    finally:
        window.close()
