"""Painting the world: inches become pixels here, never in the model (DESIGN §1).

What the maze, zones, block and robot are drawn as is :mod:`simmer.scene`'s (the window's
look); :func:`paint_items` is its pygame adapter, drawing through a :class:`Renderer`.
The static layer (background, floor tiles, zones, walls, inch rulers) is painted once per
window size from the configuration and maze; the dynamic layer (block, robot, device
outlines, sensor measurements) every frame from a :class:`~simmer.view.snapshot.Snapshot`,
never from the live simulation, so painting can run in another thread than the one stepping
it.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from simmer.colors import (
    BLACK_TILE,
    DROPOFF_COLOR,
    GHOST_COLOR,
    LOADING_COLOR,
    RULER_COLOR,
    TARGET_COLOR,
    TRAIL_COLOR,
    WHITE_TILE,
    Color,
    Point,
    tint,
)
from simmer.config.zones import Zones, zones_shown
from simmer.devices.base import Circle, Segment
from simmer.geometry import FloatArray
from simmer.scene import (
    Grid,
    Item,
    Label,
    Lines,
    Look,
    Outline,
    Palette,
    Walls,
    block_items,
    maze_items,
    robot_items,
    target_items,
)
from simmer.ui.render import Renderer
from simmer.view.snapshot import HasScene, Snapshot

PANEL_HEIGHT = 112
"""Pixels above the maze reserved for the heads-up display."""


@dataclass(frozen=True)
class View:
    """Where the maze sits in the window: pixels per inch and the pixel of the maze origin."""

    ppi: float
    ox: float
    oy: float

    @classmethod
    def fit(cls, scene: HasScene, size: tuple[int, int]) -> View:
        """The largest view of the maze (plus border) that fits under the HUD panel."""
        settings = scene.config.settings
        base_w, base_h = base_scene_size(scene)
        avail_h = max(1, size[1] - PANEL_HEIGHT)
        scale = min(size[0] / base_w, avail_h / base_h)
        border = settings.border_pixels * scale
        ox = (size[0] - base_w * scale) / 2 + border
        oy = PANEL_HEIGHT + (avail_h - base_h * scale) / 2 + border
        return cls(settings.ppi * scale, ox, oy)

    def point(self, x: float, y: float) -> Point:
        """The pixel of a world point (inches)."""
        return (self.ox + x * self.ppi, self.oy + y * self.ppi)

    def points(self, polygon: FloatArray) -> list[Point]:
        """The pixels of a (K, 2) world polygon."""
        ppi, ox, oy = self.ppi, self.ox, self.oy
        return [(ox + x * ppi, oy + y * ppi) for x, y in polygon.tolist()]

    def to_world(self, px: float, py: float) -> tuple[float, float]:
        """The world point (inches) under a pixel."""
        return ((px - self.ox) / self.ppi, (py - self.oy) / self.ppi)

    def width(self, inches: float) -> int:
        """A line thickness in whole pixels (at least one)."""
        return max(1, round(inches * self.ppi))


def base_scene_size(scene: HasScene) -> tuple[float, float]:
    """Maze plus border at the configured ``ppi``, in pixels (without the HUD panel)."""
    settings = scene.config.settings
    border = 2 * settings.border_pixels
    return (scene.maze.width * settings.ppi + border, scene.maze.height * settings.ppi + border)


def default_window_size(scene: HasScene) -> tuple[int, int]:
    """The window size at the configured ``ppi`` (1576 × 920 for the default maze)."""
    width, height = base_scene_size(scene)
    return (math.ceil(width), math.ceil(height) + PANEL_HEIGHT)


def paint_items(r: Renderer, view: View, items: list[Item]) -> None:
    """Draw a window scene's items (:mod:`simmer.scene`, :attr:`~simmer.scene.Look.WINDOW`)
    in order, inches made pixels: grid cells' edges on whole pixels so neighbours meet."""
    for item in items:
        if isinstance(item, Grid):
            _paint_grid(r, view, item)
        elif isinstance(item, Walls):
            half = item.width / 2
            for x1, y1, x2, y2 in item.lines.tolist():
                a = view.point(min(x1, x2) - half, min(y1, y2) - half)
                b = view.point(max(x1, x2) + half, max(y1, y2) + half)
                r.draw_rect((a[0], a[1], b[0] - a[0], b[1] - a[1]), item.color)
        elif isinstance(item, Lines):
            width = view.width(item.width)
            for start, end in item.lines:
                r.draw_segment(view.point(*start), view.point(*end), item.color, width)
        elif isinstance(item, Label):
            size = max(10, round(view.ppi * item.size))
            r.draw_text(item.text, view.point(*item.at), item.color, size)
        elif isinstance(item, Outline):
            points = view.points(item.points)
            if item.fill is not None:
                r.draw_polygon(points, item.fill)
            if item.edge is not None:
                r.draw_polygon(points, item.edge, view.width(item.width))
        else:
            raise ValueError(f"the window does not draw {type(item).__name__}")


def _paint_grid(r: Renderer, view: View, grid: Grid) -> None:
    """A grid's drawn cells, each a rectangle between whole-pixel edges."""
    rows, cols = grid.rgba.shape[:2]
    xs = [round(view.ox + min(c * grid.cell, grid.width) * view.ppi) for c in range(cols + 1)]
    ys = [round(view.oy + min(i * grid.cell, grid.height) * view.ppi) for i in range(rows + 1)]
    shown = grid.rgba[..., 3] > 0
    colors = grid.rgba[..., :3].tolist()
    for row, col in zip(*np.nonzero(shown), strict=True):
        red, green, blue = colors[row][col]
        rect = (xs[col], ys[row], xs[col + 1] - xs[col], ys[row + 1] - ys[row])
        r.draw_rect(rect, (red, green, blue))


class ScenePainter:
    """Draws one simulation's maze, block, robot and sensors with any :class:`Renderer`.

    ``scene``: a :class:`~simmer.view.snapshot.StaticScene` (or the simulation itself, read
    only here, for its configuration and maze).
    """

    def __init__(self, scene: HasScene) -> None:
        settings = scene.config.settings
        self.settings = settings
        self.maze = scene.maze
        self.palette = Palette.of(settings)
        self.robot_fill = self.palette.robot_fill
        self.panel_color = tint(settings.background_color, 0.6, (0, 0, 0))
        self.zones = Zones.from_settings(settings) if zones_shown(scene.config) else None
        self.static_items = maze_items(self.maze, settings, Look.WINDOW, self.zones)

    def colors(self) -> list[Color]:
        """The flat colours this painter paints with (a GIF's palette keeps them exact)."""
        settings = self.settings
        return [
            settings.background_color,
            self.panel_color,
            WHITE_TILE,
            BLACK_TILE,
            self.palette.solid_cell,
            settings.wall_color,
            RULER_COLOR,
            settings.block_color,
            self.palette.block_edge,
            settings.robot_color,
            self.robot_fill,
            GHOST_COLOR,
            TRAIL_COLOR,
            LOADING_COLOR,
            DROPOFF_COLOR,
            TARGET_COLOR,
        ]

    # ----------------------------------------------------------------- static layer

    def paint_static(self, r: Renderer, view: View, size: tuple[int, int]) -> None:
        """Background, HUD panel, the maze (floor tiles, solid cells, zones, walls) and inch
        rulers."""
        settings = self.settings
        r.fill(settings.background_color)
        r.draw_rect((0, 0, size[0], PANEL_HEIGHT), self.panel_color)
        paint_items(r, view, self.static_items)
        self._paint_rulers(r, view)

    def _paint_rulers(self, r: Renderer, view: View) -> None:
        """Inch marks every cell along the top and left borders, if there is room."""
        border = view.ox - 2
        size = min(16, int(border))
        if size < 10:
            return
        maze = self.maze
        for c in range(maze.cols + 1):
            x, y = view.point(c * maze.cell, 0)
            label = f"{c * maze.cell:g}" + (" in" if c == 0 else "")
            r.draw_text(label, (x + 2, y - size), RULER_COLOR, size)
        for row in range(1, maze.rows + 1):
            x, y = view.point(0, row * maze.cell)
            r.draw_text(f"{row * maze.cell:g}", (x - border, y - size), RULER_COLOR, size)
        self._paint_axes(r, view, size)

    def _paint_axes(self, r: Renderer, view: View, size: int) -> None:
        """The axes mark at the origin, in the rulers' margins: +x to the right along the top,
        +y down the left side (y grows downward on screen), each an arrow and its letter,
        within the first cell so that no ruler label is covered."""
        x0, y0 = view.point(0, 0)
        reach = min(view.ppi * self.maze.cell * 0.55, 110)
        top = y0 - size / 2
        start = x0 + size * 2.2  # after "0 in"
        end = start + reach * 0.6
        r.draw_segment((start, top), (end, top), RULER_COLOR, 2)
        r.draw_polygon([(end + 6, top), (end, top - 4), (end, top + 4)], RULER_COLOR)
        r.draw_text("x", (end + 9, y0 - size - 1), RULER_COLOR, size)
        left = x0 - (view.ox - 2) / 2
        first = y0 + size * 0.2
        r.draw_text("y", (left - size * 0.2, first), RULER_COLOR, size)
        down = first + size + reach * 0.6
        r.draw_segment((left, first + size), (left, down), RULER_COLOR, 2)
        r.draw_polygon([(left, down + 6), (left - 4, down), (left + 4, down)], RULER_COLOR)

    def paint_trail(self, r: Renderer, view: View, points: FloatArray) -> None:
        """The trail's ``points`` (world inches; a NaN row splits it) as lines, each piece of
        two points or more (3 px wide at the default 16 ppi, 2 px at least)."""
        width = max(2, round(view.ppi / 6))
        valid = np.concatenate(([0], ~np.isnan(points[:, 0]), [0])).astype(np.int8)
        edges = np.flatnonzero(np.diff(valid))  # each piece's first row, and the row after it
        for start, stop in zip(edges[::2].tolist(), edges[1::2].tolist(), strict=True):
            if stop - start >= 2:  # a NaN row per point off the rays (_near_shapes): skip them
                r.draw_lines(view.points(points[start:stop]), TRAIL_COLOR, width)

    # ----------------------------------------------------------------- dynamic layer

    def paint_dynamic(
        self, r: Renderer, view: View, snap: Snapshot, trail: FloatArray | None = None
    ) -> None:
        """Measurements (the sensors' rays), then the path so far where they cross it (the
        static layer's ``trail``, None: not shown), then block, robot (with a heading mark),
        visible devices, drag ghost: a ray back along a short drive once hid the path."""
        settings = self.settings
        line = max(1, round(view.ppi / 8))  # 2 px at the default 16 ppi: visible on white tiles
        for shape in snap.shapes:
            if isinstance(shape, Segment):
                r.draw_segment(view.point(*shape.start), view.point(*shape.end), shape.color, line)
            elif isinstance(shape, Circle):
                r.draw_circle(view.point(*shape.center), shape.radius * view.ppi, shape.color, 2)
        if trail is not None and len(trail) and snap.shapes:
            self.paint_trail(r, view, _near_shapes(trail, snap.shapes))
        if self.zones is not None:
            paint_items(r, view, target_items(self.zones, snap.target, self.maze.cell))
        paint_items(r, view, block_items(snap.block, settings, Look.WINDOW))
        layout = snap.layout
        paint_items(r, view, robot_items(snap.robot[: layout.body + 2], settings, Look.WINDOW))
        points = view.points(snap.robot)
        for start, stop, color in layout.devices:
            r.draw_polygon(points[start:stop], color, 2)
        label_size = max(10, round(view.ppi * 0.9))
        for index, text, color in layout.labels:
            r.draw_text(text, points[index], color, label_size, centered=True)
        if snap.ghost is not None:
            r.draw_polygon(view.points(snap.ghost), GHOST_COLOR, 2)


def _near_shapes(points: FloatArray, shapes: Sequence[Segment | Circle]) -> FloatArray:
    """The trail's ``points`` within the measurements' bounding box (an inch around), the rest
    NaN (a NaN splits the trail): only what a ray may cover is painted again each frame, not
    a long run's whole path."""
    ends: list[tuple[float, float]] = []
    for shape in shapes:
        if isinstance(shape, Segment):
            ends += [(shape.start.x, shape.start.y), (shape.end.x, shape.end.y)]
        else:
            cx, cy, radius = shape.center.x, shape.center.y, shape.radius
            ends += [(cx - radius, cy - radius), (cx + radius, cy + radius)]
    box = np.asarray(ends, dtype=np.float64)
    (left, top), (right, bottom) = box.min(axis=0) - 1.0, box.max(axis=0) + 1.0
    x, y = points[:, 0], points[:, 1]
    inside = (x >= left) & (x <= right) & (y >= top) & (y <= bottom)
    kept = inside.copy()
    kept[1:] |= inside[:-1]  # a piece with one end inside is drawn whole
    kept[:-1] |= inside[1:]
    result = points.copy()
    result[~kept] = np.nan
    return result
