"""``simmer maze edit FILE``: a maze in a window, edited with the mouse (docs/mazes.md).

Click a cell to cycle it (solid, open, start cell, loading zone, drop-off zone); drag the robot
to move the start pose (it lands in the centre of the cell it is dropped on) and press R to turn
it 90 degrees; A shows or hides the ambiguity map (each open cell tinted by how many others look
like it to the robot's sensors, the count written in it); S or Ctrl+S saves, Esc or closing the
window quits. A maze the file formats would refuse (a zone on a solid cell, a cell that cannot
be reached, the robot on a solid cell) is not saved: the status line says why, in the words a
file's error would use. The maze is kept as its text picture's characters, so what is saved is
what ``read_text`` accepts.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import replace
from pathlib import Path

import numpy as np
import pygame

from simmer.colors import DROPOFF_COLOR, LOADING_COLOR, Color
from simmer.config.mazegen import alike_counts
from simmer.config.mazes import (
    LOADING,
    OPEN,
    SOLID,
    START,
    MazeSpec,
    read_text,
    write_maze,
    write_text,
)
from simmer.config.models import Settings
from simmer.errors import ConfigError
from simmer.scene import ALIKE_COLORS
from simmer.ui.render import PygameRenderer

__all__ = ["MazeEditor", "edit_maze"]

DIGITS = "123456789"
CYCLE = (SOLID, OPEN, START, LOADING)
"""What a click makes of a cell, in turn; after the loading zone a new drop-off zone (the
lowest digit free), after a drop-off zone a solid cell again."""
STATUS_HEIGHT = 56
"""Pixels under the maze for the status line and the keys."""
MAX_CELL_PIXELS = 90
"""Pixels a cell side at most (the course maze's window is 740 x 436)."""
DEFAULT_HEADING = float(Settings.model_fields["robot_start_rotation"].default)
"""The start heading of a maze that names none (a configuration's default)."""
SOLID_COLOR: Color = (70, 70, 70)
OPEN_COLOR: Color = (250, 250, 250)
INK: Color = (20, 20, 20)
ROBOT_COLOR: Color = (200, 40, 160)


class MazeEditor:
    """The editor's state (a picture's characters, the start pose, the status line) and its
    drawing on ``surface``; :meth:`handle` takes pygame events, so a test drives it through the
    event queue exactly as a user's mouse and keys do."""

    def __init__(self, path: Path, maze: MazeSpec, surface: pygame.Surface) -> None:
        self.path = path
        self.surface = surface
        self.cell_size, self.tile, self.floor_seed, self.name = (
            maze.cell,
            maze.tile,
            maze.floor_seed,
            maze.name,
        )
        picture = write_text(maze).splitlines()[-maze.rows :]
        self.chars = [list(row) for row in picture]
        self.zone_names = {str(i + 1): name for i, name in enumerate(maze.dropoff)}
        start = maze.places()["robot_start_position"]
        heading = maze.start_pose[2] if maze.start_pose else DEFAULT_HEADING
        self.pose = [start[0], start[1], heading]
        self.show_ambiguity = True
        self.dragging = False
        self.status = f"{path}: click a cell to change it; drag the robot; R turns it; S saves"
        self.saved = False
        self._alike: np.ndarray | None = None

    # ------------------------------------------------------------------ geometry

    @property
    def rows(self) -> int:
        """Rows of cells."""
        return len(self.chars)

    @property
    def cols(self) -> int:
        """Cells in a row."""
        return len(self.chars[0])

    @property
    def pixels(self) -> float:
        """Pixels a cell side, the maze fitted above the status line."""
        width, height = self.surface.get_size()
        return min((width - 20) / self.cols, (height - STATUS_HEIGHT - 20) / self.rows)

    def cell_at(self, pos: tuple[int, int]) -> tuple[int, int] | None:
        """The (row, column) under a pixel, or None off the maze."""
        r, c = int((pos[1] - 10) // self.pixels), int((pos[0] - 10) // self.pixels)
        return (r, c) if 0 <= r < self.rows and 0 <= c < self.cols else None

    def to_pixel(self, x: float, y: float) -> tuple[float, float]:
        """The pixel of a point in inches."""
        scale = self.pixels / self.cell_size
        return (10 + x * scale, 10 + y * scale)

    def cell_centre(self, r: int, c: int) -> tuple[int, int]:
        """The pixel at the centre of a cell (where a click on it lands)."""
        x, y = self.to_pixel((c + 0.5) * self.cell_size, (r + 0.5) * self.cell_size)
        return (round(x), round(y))

    # ------------------------------------------------------------------ editing

    def text(self) -> str:
        """The maze as its text picture, as it would be saved."""
        lines = [f"name = {self.name}"] if self.name else []
        lines += [f"cell = {self.cell_size:g}", f"tile = {self.tile:g}"]
        lines += [f"floor_seed = {self.floor_seed}"]
        lines.append("start = " + ", ".join(f"{v!r}" for v in self.pose))
        used = {ch for row in self.chars for ch in row if ch in DIGITS}
        lines += [
            f"zone {d} = {name}"
            for d, name in sorted(self.zone_names.items())
            if d in used and name != f"B{d}"
        ]
        return "\n".join(lines + ["".join(row) for row in self.chars]) + "\n"

    def maze(self) -> MazeSpec:
        """The maze as a file would give it; ConfigError (line and column) if a file would be
        refused."""
        return read_text(self.text(), self.path.name)

    def cycle(self, r: int, c: int) -> None:
        """Solid, open, start cell, loading zone, a drop-off zone, solid again."""
        now = self.chars[r][c]
        if now in DIGITS:
            new = SOLID
        elif now == LOADING:
            used = {ch for row in self.chars for ch in row}
            new = next((d for d in DIGITS if d not in used), SOLID)
        else:
            new = CYCLE[(CYCLE.index(now) + 1) % len(CYCLE)] if now in CYCLE else SOLID
        self.chars[r][c] = new
        self._alike = None
        self.status = f"cell [{r}, {c}]: {_describe(new, self.zone_names)}"

    def save(self) -> bool:
        """Write the maze to the file if it is valid; the status line says what happened."""
        try:
            maze = self.maze()
        except ConfigError as exc:
            self.status = "not saved: " + exc.issues[0].render(exc.source)
            return False
        try:
            write_maze(replace(maze, name=self.name), self.path)
        except (OSError, ValueError) as exc:
            self.status = f"not saved: {exc}"
            return False
        self.saved = True
        self.status = f"saved {self.path}"
        return True

    def handle(self, event: pygame.event.Event) -> bool:
        """Take one event; False when the editor should close."""
        if event.type == pygame.QUIT:
            return False
        if event.type == pygame.KEYDOWN:
            if event.key == pygame.K_ESCAPE:
                return False
            if event.key == pygame.K_s:
                self.save()
            elif event.key == pygame.K_r:
                self.pose[2] = (self.pose[2] + 90.0) % 360.0
            elif event.key == pygame.K_a:
                self.show_ambiguity = not self.show_ambiguity
        elif event.type == pygame.MOUSEBUTTONDOWN and event.button == 1:
            rx, ry = self.to_pixel(self.pose[0], self.pose[1])
            if math.hypot(event.pos[0] - rx, event.pos[1] - ry) < self.pixels * 0.4:
                self.dragging = True
            else:
                cell = self.cell_at(event.pos)
                if cell is not None:
                    self.cycle(*cell)
        elif event.type == pygame.MOUSEMOTION and self.dragging:
            scale = self.cell_size / self.pixels
            self.pose[0] = (event.pos[0] - 10) * scale
            self.pose[1] = (event.pos[1] - 10) * scale
        elif event.type == pygame.MOUSEBUTTONUP and event.button == 1 and self.dragging:
            self.dragging = False
            cell = self.cell_at(event.pos)
            if cell is not None:
                self.pose[0] = (cell[1] + 0.5) * self.cell_size
                self.pose[1] = (cell[0] + 0.5) * self.cell_size
                self.status = f"start pose: cell [{cell[0]}, {cell[1]}], heading {self.pose[2]:g}"
        return True

    def frame(self) -> bool:
        """Take every event waiting in pygame's queue, then draw; False once closed."""
        running = True
        for event in pygame.event.get():
            running = self.handle(event) and running
        self.draw()
        return running

    # ------------------------------------------------------------------ drawing

    def alike(self) -> np.ndarray:
        """How many other cells look like each open cell (-1 on solid ones)."""
        if self._alike is None:
            opened = np.array([[ch != SOLID for ch in row] for row in self.chars])
            self._alike = alike_counts(opened, self.cell_size, 1.0)
        return self._alike

    def draw(self) -> None:
        """The maze, its zones, the ambiguity map, the robot at its start and the status."""
        r = PygameRenderer(self.surface)
        r.fill((235, 235, 235))
        px = self.pixels
        alike = self.alike() if self.show_ambiguity else None
        text_size = max(10, round(px * 0.22))
        for row, line in enumerate(self.chars):
            for col, ch in enumerate(line):
                x, y = self.to_pixel(col * self.cell_size, row * self.cell_size)
                rect = (x, y, math.ceil(px), math.ceil(px))
                if ch == SOLID:
                    r.draw_rect(rect, SOLID_COLOR)
                    continue
                fill = OPEN_COLOR
                if alike is not None:
                    fill = _blend(ALIKE_COLORS[min(int(alike[row, col]), len(ALIKE_COLORS) - 1)])
                r.draw_rect(rect, fill)
                r.draw_rect(rect, (190, 190, 190), 1)
                if ch == LOADING or ch in DIGITS:
                    colour = LOADING_COLOR if ch == LOADING else DROPOFF_COLOR
                    inset = (x + 3, y + 3, math.ceil(px) - 6, math.ceil(px) - 6)
                    r.draw_rect(inset, colour, max(2, round(px * 0.05)))
                label = {LOADING: "L", START: "S"}.get(ch, self.zone_names.get(ch, f"B{ch}"))
                if ch != OPEN:
                    r.draw_text(label, (x + 6, y + 4), INK, text_size)
                if alike is not None:
                    centre = (x + px * 0.8, y + px * 0.8)  # a corner: the robot sits mid-cell
                    r.draw_text(str(int(alike[row, col])), centre, INK, text_size, centered=True)
        self._draw_robot(r, px)
        height = self.surface.get_height()
        status_colour = (170, 20, 20) if self.status.startswith("not saved") else INK
        r.draw_text(self.status[:160], (10, height - STATUS_HEIGHT + 6), status_colour, 15)
        keys = "click: cycle a cell   drag the robot: start   R: turn   A: ambiguity map   S: save"
        r.draw_text(keys, (10, height - 24), (90, 90, 90), 13)

    def _draw_robot(self, r: PygameRenderer, px: float) -> None:
        x, y = self.to_pixel(self.pose[0], self.pose[1])
        radius = px * 0.28
        r.draw_circle((x, y), radius, ROBOT_COLOR, 3)
        heading = math.radians(self.pose[2])  # degrees from +y, counter-clockwise
        tip = (x - math.sin(heading) * radius * 1.5, y + math.cos(heading) * radius * 1.5)
        r.draw_segment((x, y), tip, ROBOT_COLOR, 3)


def _describe(ch: str, names: dict[str, str]) -> str:
    if ch in DIGITS:
        return f"drop-off zone {names.get(ch, 'B' + ch)}"
    return {SOLID: "solid", OPEN: "open", START: "start cell", LOADING: "loading zone"}[ch]


def _blend(colour: Color, amount: float = 0.45) -> Color:
    """``colour`` mixed with white (a pale tint that text stays readable on)."""
    return (
        round(255 + (colour[0] - 255) * amount),
        round(255 + (colour[1] - 255) * amount),
        round(255 + (colour[2] - 255) * amount),
    )


def window_size(maze: MazeSpec) -> tuple[int, int]:
    """A window that shows every cell at up to :data:`MAX_CELL_PIXELS` pixels, within 1200 x
    800."""
    px = min(MAX_CELL_PIXELS, 1180 / maze.cols, (780 - STATUS_HEIGHT) / maze.rows)
    return (max(640, round(px * maze.cols) + 20), round(px * maze.rows) + 20 + STATUS_HEIGHT)


def edit_maze(path: Path, maze: MazeSpec, stop: Callable[[], bool] = lambda: False) -> bool:
    """Open the editor's window on ``maze`` (saved to ``path``) until it is closed or ``stop()``
    (checked each frame) says so; whether it was saved."""
    pygame.display.init()
    pygame.font.init()
    try:
        pygame.display.set_caption(f"SimMeR maze editor - {path.name}")
        screen = pygame.display.set_mode(window_size(maze))
        editor = MazeEditor(path, maze, screen)
        clock = pygame.time.Clock()
        while editor.frame() and not stop():
            pygame.display.flip()
            clock.tick(30)
        return editor.saved
    finally:
        pygame.display.quit()
