"""Painting the world: inches become pixels here, never in the model (DESIGN §1).

The static layer (background, floor tiles, walls, inch rulers) is painted once per window size
from the configuration and maze; the dynamic layer (block, robot, device outlines, sensor
measurements) every frame from a :class:`~simmer.view.snapshot.Snapshot`, never from the live
simulation, so painting can run in another thread than the one stepping it.
"""

from __future__ import annotations

import math
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
)
from simmer.config.zones import Zone, Zones, zones_shown
from simmer.devices.base import Circle, Segment
from simmer.geometry import FloatArray
from simmer.ui.render import Renderer
from simmer.view.snapshot import HasScene, Snapshot

PANEL_HEIGHT = 112
"""Pixels above the maze reserved for the heads-up display."""
ZONE_INSET = 0.7
"""Inches between a zone's outline and the walls, so both show."""
ZONE_LINE = 0.45
"""Inches: the width of a zone's outline."""


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


def tint(color: Color, amount: float, toward: Color = (255, 255, 255)) -> Color:
    """``color`` moved ``amount`` (0..1) of the way toward ``toward``."""
    r, g, b = (round(c + (t - c) * amount) for c, t in zip(color, toward, strict=True))
    return (r, g, b)


class ScenePainter:
    """Draws one simulation's maze, block, robot and sensors with any :class:`Renderer`.

    ``scene``: a :class:`~simmer.view.snapshot.StaticScene` (or the simulation itself, read
    only here, for its configuration and maze).
    """

    def __init__(self, scene: HasScene) -> None:
        settings = scene.config.settings
        self.settings = settings
        self.maze = scene.maze
        self.robot_fill = tint(settings.robot_color, 0.75)
        self.solid_color = tint(settings.background_color, 0.35, (0, 0, 0))
        self.panel_color = tint(settings.background_color, 0.6, (0, 0, 0))
        self.block_edge = tint(settings.block_color, 0.5, (0, 0, 0))
        self.zones = Zones.from_settings(settings) if zones_shown(scene.config) else None

    def colors(self) -> list[Color]:
        """The flat colours this painter paints with (a GIF's palette keeps them exact)."""
        settings = self.settings
        return [
            settings.background_color,
            self.panel_color,
            WHITE_TILE,
            BLACK_TILE,
            self.solid_color,
            settings.wall_color,
            RULER_COLOR,
            settings.block_color,
            self.block_edge,
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
        """Background, HUD panel, floor tiles, solid cells, walls and inch rulers."""
        settings = self.settings
        maze = self.maze
        r.fill(settings.background_color)
        r.draw_rect((0, 0, size[0], PANEL_HEIGHT), self.panel_color)
        tile = maze.tile
        rows, cols = maze.floor_white.shape
        xs = [round(view.ox + min(c * tile, maze.width) * view.ppi) for c in range(cols + 1)]
        ys = [round(view.oy + min(r_ * tile, maze.height) * view.ppi) for r_ in range(rows + 1)]
        for row in range(rows):
            for col in range(cols):
                color = WHITE_TILE if maze.floor_white[row, col] else BLACK_TILE
                r.draw_rect((xs[col], ys[row], xs[col + 1] - xs[col], ys[row + 1] - ys[row]), color)
        cell = maze.cell
        for row, col in zip(*np.nonzero(maze.solid), strict=True):
            x0, y0 = view.point(col * cell, row * cell)
            x1, y1 = view.point((col + 1) * cell, (row + 1) * cell)
            r.draw_rect(
                (round(x0), round(y0), round(x1) - round(x0), round(y1) - round(y0)),
                self.solid_color,
            )
        if self.zones is not None:
            for zone in self.zones.all():
                color = LOADING_COLOR if zone is self.zones.loading else DROPOFF_COLOR
                self.paint_zone(r, view, zone, color)
        half = settings.wall_thickness / 2
        for x1, y1, x2, y2 in maze.segments.tolist():
            a = view.point(min(x1, x2) - half, min(y1, y2) - half)
            b = view.point(max(x1, x2) + half, max(y1, y2) + half)
            r.draw_rect((a[0], a[1], b[0] - a[0], b[1] - a[1]), settings.wall_color)
        self._paint_rulers(r, view)

    def paint_zone(self, r: Renderer, view: View, zone: Zone, color: Color) -> None:
        """A zone's outline just inside its cells (no line between two of its cells), and its
        name in its first cell's corner."""
        cell = self.maze.cell
        cells = set(zone.cells)
        width = view.width(ZONE_LINE)
        inset = ZONE_INSET
        for row, col in zone.cells:
            x0, y0 = col * cell + inset, row * cell + inset
            x1, y1 = (col + 1) * cell - inset, (row + 1) * cell - inset
            # extend along a side shared with the zone's next cell, so the outline is unbroken
            left = x0 - 2 * inset if (row, col - 1) in cells else x0
            right = x1 + 2 * inset if (row, col + 1) in cells else x1
            top = y0 - 2 * inset if (row - 1, col) in cells else y0
            bottom = y1 + 2 * inset if (row + 1, col) in cells else y1
            sides = [
                ((row - 1, col), (left, y0), (right, y0)),
                ((row + 1, col), (left, y1), (right, y1)),
                ((row, col - 1), (x0, top), (x0, bottom)),
                ((row, col + 1), (x1, top), (x1, bottom)),
            ]
            for near, a, b in sides:
                if near not in cells:
                    r.draw_segment(view.point(*a), view.point(*b), color, width)
        row, col = min(zone.cells)
        size = max(10, round(view.ppi * 1.1))
        corner = view.point(col * cell + 2 * inset, row * cell + 2 * inset)
        r.draw_text(zone.name, corner, color, size)

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

    def paint_trail(self, r: Renderer, view: View, points: FloatArray) -> None:
        """The trail's ``points`` (world inches; a NaN row splits it) as lines, each piece of
        two points or more (3 px wide at the default 16 ppi, 2 px at least)."""
        width = max(2, round(view.ppi / 6))
        gaps = np.flatnonzero(np.isnan(points[:, 0]))
        for piece in np.split(points, gaps):
            pixels = view.points(piece[~np.isnan(piece[:, 0])])
            if len(pixels) >= 2:
                r.draw_lines(pixels, TRAIL_COLOR, width)

    # ----------------------------------------------------------------- dynamic layer

    def paint_dynamic(self, r: Renderer, view: View, snap: Snapshot) -> None:
        """Block, robot (with a heading mark), visible devices, measurements, drag ghost."""
        settings = self.settings
        if self.zones is not None and snap.target in self.zones.dropoff:
            self.paint_zone(r, view, self.zones.dropoff[snap.target], TARGET_COLOR)
        block_px = view.points(snap.block)
        r.draw_polygon(block_px, settings.block_color)
        r.draw_polygon(block_px, self.block_edge, view.width(settings.block_thickness))
        layout = snap.layout
        points = view.points(snap.robot)
        body = points[: layout.body]
        thickness = view.width(settings.robot_thickness)
        r.draw_polygon(body, self.robot_fill)
        r.draw_polygon(body, settings.robot_color, thickness)
        mark = layout.body
        r.draw_segment(points[mark], points[mark + 1], settings.robot_color, thickness)
        for start, stop, color in layout.devices:
            r.draw_polygon(points[start:stop], color, 2)
        label_size = max(10, round(view.ppi * 0.9))
        for index, text, color in layout.labels:
            r.draw_text(text, points[index], color, label_size, centered=True)
        line = max(1, round(view.ppi / 8))  # 2 px at the default 16 ppi: visible on white tiles
        for shape in snap.shapes:
            if isinstance(shape, Segment):
                r.draw_segment(view.point(*shape.start), view.point(*shape.end), shape.color, line)
            elif isinstance(shape, Circle):
                r.draw_circle(view.point(*shape.center), shape.radius * view.ppi, shape.color, 2)
        if snap.ghost is not None:
            r.draw_polygon(view.points(snap.ghost), GHOST_COLOR, 2)
