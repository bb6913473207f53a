"""What the maze, its zones, the block and the robot are drawn as: one description, in world
inches, that the window (:mod:`simmer.ui.scene`) and the pictures on a page
(:mod:`simmer.record.page`: a run's plots, a sweep's pictures) each only draw.

As pymunk's draw options draw a space's shapes, an adapter draws a list of *items* (:class:`Grid`,
:class:`Walls`, :class:`Cells`, :class:`Lines`, :class:`Label`, :class:`Outline`,
:class:`Arrow`) and decides nothing about the maze: which shapes, which colours (from
:mod:`simmer.colors` and the settings) and which layer are decided here. A :class:`Look` says
where the items go, for the differences are the pictures' own: the window outlines the zones and
fills the robot; a run's path plot tints the zones' cells and outlines the robot over the path;
a sweep's map is the maze in greys under its own colours.

Neither pygame nor matplotlib is imported here.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from enum import Enum
from typing import Any

import numpy as np

from simmer.colors import (
    BLACK_TILE,
    COLLISION_COLOR,
    DROPOFF_COLOR,
    LOADING_COLOR,
    MAP_INK,
    MAP_SOLID,
    MAP_ZONE,
    TARGET_COLOR,
    WHITE_TILE,
    Color,
    Point,
    tint,
)
from simmer.config.maze import Block, Maze, robot_outline
from simmer.config.models import Settings
from simmer.config.zones import Zone, Zones
from simmer.geometry import FloatArray, Pose, place_polygon

RGBA = np.ndarray[Any, np.dtype[np.uint8]]


class Look(Enum):
    """Where a scene is drawn, which decides what its parts are drawn as, and the unit of its
    widths and text sizes."""

    WINDOW = "window"
    """The window and its videos: widths and text sizes in inches of the world."""
    PAGE = "page"
    """A run's path plot: widths and text sizes in points of the page."""
    MAP = "map"
    """A sweep's pictures: the maze in greys (solid cells, zones, black walls) under what the
    picture colours; points of the page."""


ZONE_INSET = 0.7
"""Inches between a zone's outline and the walls in the window, so both show."""
ZONE_LINE = 0.45
"""Inches: the width of a zone's outline in the window."""
ZONE_ALPHA = 0.28
"""How opaque a zone's tint over the floor is on a run's path plot."""

# The layers of a picture, bottom up (matplotlib's z-order; the window draws a list in order).
FLOOR, SOLID, ZONE, WALL, ZONE_NAME, ROBOT, BLOCK = 1.0, 2.0, 2.5, 3.0, 3.2, 3.5, 5.0
MAP_CELLS, MAP_WALLS, MAP_NAMES = 1.0, 2.0, 3.0
"""A sweep map's layers: matplotlib's own for patches, lines and text, so what the picture adds
after (each start cell's colour, patches) lies over the cells and under the walls."""


@dataclass(frozen=True)
class Grid:
    """Square cells of side ``cell`` from the maze's origin, cut at ``width`` x ``height``
    inches; ``rgba[row, col]`` colours each (alpha 0: not drawn). The floor, the solid cells."""

    cell: float
    width: float
    height: float
    rgba: RGBA
    layer: float


@dataclass(frozen=True)
class Walls:
    """The walls' centre lines (N, 4: x1, y1, x2, y2, axis-aligned), each a slab ``width``
    thick whose ends reach half its width past the line's, so corners close."""

    lines: FloatArray
    color: Color
    width: float
    layer: float


@dataclass(frozen=True)
class Cells:
    """Rectangles (x, y, w, h, inches) filled with ``color`` at ``alpha``, no edge."""

    rects: tuple[tuple[float, float, float, float], ...]
    color: Color
    alpha: float
    layer: float


@dataclass(frozen=True)
class Lines:
    """Straight lines (start, end), ``width`` thick."""

    lines: tuple[tuple[Point, Point], ...]
    color: Color
    width: float
    layer: float


@dataclass(frozen=True)
class Label:
    """One line of text whose top-left corner is at ``at``; ``boxed``: bold, on a pale box."""

    text: str
    at: Point
    color: Color
    size: float
    layer: float
    boxed: bool = False


@dataclass(frozen=True)
class Outline:
    """A closed polygon (K, 2): filled with ``fill`` and/or edged with ``edge``."""

    points: FloatArray
    fill: Color | None
    edge: Color | None
    width: float
    layer: float
    dashed: bool = False


@dataclass(frozen=True)
class Arrow:
    """A line from ``start`` with an arrowhead at ``end``."""

    start: Point
    end: Point
    color: Color
    width: float
    layer: float


Item = Grid | Walls | Cells | Lines | Label | Outline | Arrow


@dataclass(frozen=True)
class Palette:
    """The colours the window tints from the settings' own, for the scene and a video's palette."""

    solid_cell: Color
    """A solid cell: the background darkened (a path plot shows it the same)."""
    robot_fill: Color
    """Inside the robot's outline: its colour, paled."""
    block_edge: Color
    """The block's edge in the window: its colour, darkened."""

    @classmethod
    def of(cls, settings: Settings) -> Palette:
        """The palette of one configuration's settings."""
        return cls(
            solid_cell=tint(settings.background_color, 0.35, (0, 0, 0)),
            robot_fill=tint(settings.robot_color, 0.75),
            block_edge=tint(settings.block_color, 0.5, (0, 0, 0)),
        )


def maze_items(
    maze: Maze,
    settings: Settings,
    look: Look,
    zones: Zones | None = None,
    target: str | None = None,
) -> list[Item]:
    """The maze drawn as ``look`` draws it, bottom layer first: the floor's tiles (not on a
    map), the solid cells, each of ``zones`` (named; on a page ``target``'s in the target's
    colour) and the walls."""
    items: list[Item] = []
    if look is not Look.MAP:
        floor = np.where(maze.floor_white[..., None], (*WHITE_TILE, 255), (*BLACK_TILE, 255))
        items.append(Grid(maze.tile, maze.width, maze.height, floor.astype(np.uint8), FLOOR))
    solid = np.zeros((*maze.solid.shape, 4), dtype=np.uint8)
    solid[maze.solid] = (*(MAP_SOLID if look is Look.MAP else Palette.of(settings).solid_cell), 255)
    layer = MAP_CELLS if look is Look.MAP else SOLID
    items.append(Grid(maze.cell, maze.width, maze.height, solid, layer))
    if zones is not None:
        for zone in zones.all():
            color = LOADING_COLOR if zone is zones.loading else DROPOFF_COLOR
            if look is Look.PAGE and zone.name == target:
                color = TARGET_COLOR
            items += zone_items(zone, color, maze.cell, look)
    if look is Look.WINDOW:
        items.append(Walls(maze.segments, settings.wall_color, settings.wall_thickness, WALL))
    elif look is Look.PAGE:
        items.append(Walls(maze.segments, settings.wall_color, 2.5, WALL))
    else:
        items.append(Walls(maze.segments, MAP_INK, 2.0, MAP_WALLS))
    return sorted(items, key=lambda item: item.layer)  # stable: a zone's name after its shape


def zone_items(zone: Zone, color: Color, cell: float, look: Look) -> list[Item]:
    """One zone, named in its first cell's corner: in the window an outline just inside its
    cells (no line between two of its cells); on a page its cells tinted ``color``; on a map
    its cells pale."""
    row, col = min(zone.cells)
    if look is Look.MAP:
        rects = tuple((c * cell, r * cell, cell, cell) for r, c in zone.cells)
        corner = (col * cell + 0.8, row * cell + 0.8)
        return [
            Cells(rects, MAP_ZONE, 1.0, MAP_CELLS),
            Label(zone.name, corner, MAP_INK, 7, MAP_NAMES),
        ]
    if look is Look.PAGE:
        rects = tuple((c * cell, r * cell, cell, cell) for r, c in zone.cells)
        corner = (col * cell + 0.6, row * cell + 0.6)
        return [
            Cells(rects, color, ZONE_ALPHA, ZONE),
            Label(zone.name, corner, color, 9, ZONE_NAME, boxed=True),
        ]
    cells = set(zone.cells)
    inset = ZONE_INSET
    lines: list[tuple[Point, Point]] = []
    for row_, col_ in zone.cells:
        x0, y0 = col_ * cell + inset, row_ * cell + inset
        x1, y1 = (col_ + 1) * cell - inset, (row_ + 1) * cell - inset
        # extend along a side shared with the zone's next cell, so the outline is unbroken
        left = x0 - 2 * inset if (row_, col_ - 1) in cells else x0
        right = x1 + 2 * inset if (row_, col_ + 1) in cells else x1
        top = y0 - 2 * inset if (row_ - 1, col_) in cells else y0
        bottom = y1 + 2 * inset if (row_ + 1, col_) in cells else y1
        sides = [
            ((row_ - 1, col_), (left, y0), (right, y0)),
            ((row_ + 1, col_), (left, y1), (right, y1)),
            ((row_, col_ - 1), (x0, top), (x0, bottom)),
            ((row_, col_ + 1), (x1, top), (x1, bottom)),
        ]
        lines += [(a, b) for near, a, b in sides if near not in cells]
    corner = (col * cell + 2 * inset, row * cell + 2 * inset)
    return [Lines(tuple(lines), color, ZONE_LINE, ZONE), Label(zone.name, corner, color, 1.1, ZONE)]


def target_items(zones: Zones, target: str | None, cell: float) -> list[Item]:
    """The window's mark of a run's target zone, over its drop-off outline (nothing if the
    target is not a drop-off zone)."""
    zone = zones.dropoff.get(target) if target is not None else None
    return zone_items(zone, TARGET_COLOR, cell, Look.WINDOW) if zone is not None else []


def placed_block(settings: Settings, at: tuple[float, float] | None = None) -> FloatArray:
    """The block's outline where the settings put it, or at ``at`` (a project run's drawn
    place), at its configured rotation."""
    block = Block.from_settings(settings)
    if at is not None:
        block.place(*at, block.rotation)
    return block.polygon


def put_down_block(
    settings: Settings,
    at: tuple[float, float] | None,
    picked: tuple[float, float, float],
    put: tuple[float, float, float],
) -> FloatArray:
    """The block's outline where a gripper put it down: it lay at ``at`` (None: where the
    settings put it), was taken with the robot at pose ``picked`` and kept its place relative
    to the robot (as the simulation carries it) until the robot was at pose ``put``."""
    block = Block.from_settings(settings)
    if at is not None:
        block.place(*at, block.rotation)
    block.hold(Pose(*picked))
    block.place(*block.carried_pose(Pose(*put)))
    return block.polygon


def block_items(polygon: FloatArray, settings: Settings, look: Look) -> list[Item]:
    """The block at ``polygon``: filled in its colour, edged darker (in the window as thick
    as ``block_thickness``) or black on a page."""
    if look is Look.WINDOW:
        edge, width = Palette.of(settings).block_edge, settings.block_thickness
    else:
        edge, width = (0, 0, 0), 1.0
    return [Outline(polygon, settings.block_color, edge, width, BLOCK)]


def heading_mark(outline: FloatArray, look: Look) -> FloatArray:
    """The robot's heading mark in its own frame (2, 2): from its centre straight ahead, short
    inside the body in the window, past it as an arrow on a page."""
    if look is Look.WINDOW:
        reach = 0.3 * float(np.min(np.abs(outline).max(axis=0)))
    else:
        reach = 1.4 * float(np.abs(outline).max())
    return np.array([[0.0, 0.0], [0.0, reach]])


def placed_robot(settings: Settings, pose: tuple[float, float, float]) -> FloatArray:
    """The robot's outline and then its page heading mark (K + 2, 2) at ``pose``."""
    outline = robot_outline(settings)
    local = np.concatenate((outline, heading_mark(outline, Look.PAGE)))
    placed = np.empty_like(local)
    place_polygon(local, *pose, placed)
    return placed


def robot_items(
    placed: FloatArray, settings: Settings, look: Look, color: Color | None = None,
    dashed: bool = False,
) -> list[Item]:  # fmt: skip
    """The robot whose outline and then heading mark (K + 2, 2) are ``placed``: in the window
    filled pale, edged and marked in its colour ``robot_thickness`` wide; on a page an outline
    in ``color`` (dashed or not) and an arrow along its heading, under the path."""
    body, (start, end) = placed[:-2], placed[-2:].tolist()
    if look is Look.WINDOW:
        edge, width = settings.robot_color, settings.robot_thickness
        return [
            Outline(body, Palette.of(settings).robot_fill, edge, width, ROBOT),
            Lines((((start[0], start[1]), (end[0], end[1])),), edge, width, ROBOT),
        ]
    edge = color if color is not None else settings.robot_color
    return [
        Outline(body, None, edge, 2.0, ROBOT, dashed),
        Arrow((start[0], start[1]), (end[0], end[1]), edge, 2.0, ROBOT),
    ]


ALIKE_COLORS: tuple[Color, ...] = ((46, 160, 67), (255, 200, 40), (245, 130, 30), (215, 40, 40))
"""An ambiguity map's tints: no look-alike, 1, 2, 3 or more."""


def ambiguity_items(alike: np.ndarray, cell: float) -> list[Item]:
    """An ambiguity map: each open cell tinted by how many other cells look like it to the
    robot's sensors (``alike[row, col]``, -1 on solid cells), its count written in it."""
    items: list[Item] = []
    for shade, color in enumerate(ALIKE_COLORS):
        chosen = alike >= shade if shade == len(ALIKE_COLORS) - 1 else alike == shade
        rects = tuple(
            (c * cell, r * cell, cell, cell) for r, c in zip(*np.nonzero(chosen), strict=True)
        )
        if rects:
            items.append(Cells(rects, color, 0.55, ZONE))
    for r, c in zip(*np.nonzero(alike >= 0), strict=True):
        at = (float(c + 0.38) * cell, float(r + 0.3) * cell)
        items.append(Label(str(int(alike[r, c])), at, (0, 0, 0), 10, ZONE_NAME))
    return items


def open_cell_items(
    walls: Sequence[Sequence[int]], cell: float, color: Color, alpha: float = 0.5
) -> list[Item]:
    """Every open cell of a ``walls`` matrix tinted ``color`` over a map (a sweep's mazes.png
    colours each maze by its runs' success rate), above the solid cells, under the walls."""
    rects = tuple(
        (c * cell, r * cell, cell, cell)
        for r, row in enumerate(walls)
        for c, code in enumerate(row)
        if code
    )
    return [Cells(rects, color, alpha, (MAP_CELLS + MAP_WALLS) / 2)]


COMPARED_TRAIL = 0.25
"""Inches: the width of a run's path when runs are side by side."""


def compared_run_items(
    placed: FloatArray,
    block: FloatArray,
    trail: FloatArray | None,
    color: Color,
    settings: Settings,
    collided: bool,
) -> list[Item]:
    """One run of several side by side in the window (``simmer replay RUN_A RUN_B``): its
    path so far (``trail``, (N, 2) with NaN rows between pieces), its block edged and its
    robot (outline and heading mark ``placed``, K + 2 rows) filled in its ``color``, and a red
    cross over the robot once it has ``collided``."""
    items: list[Item] = []
    if trail is not None and len(trail) >= 2:
        ends = np.stack((trail[:-1], trail[1:]), axis=1)  # (N - 1, 2, 2)
        ends = ends[~np.isnan(ends).any(axis=(1, 2))]
        lines = tuple(((a, b), (c, d)) for (a, b), (c, d) in ends.tolist())
        items.append(Lines(lines, color, COMPARED_TRAIL, ZONE_NAME))
    items.append(Outline(block, settings.block_color, color, settings.block_thickness, BLOCK))
    body, (start, end) = placed[:-2], placed[-2:].tolist()
    width = settings.robot_thickness
    items += [
        Outline(body, tint(color, 0.55), color, width, ROBOT),
        Lines((((start[0], start[1]), (end[0], end[1])),), color, width, ROBOT),
    ]
    if collided:
        (x0, y0), (x1, y1) = body.min(axis=0).tolist(), body.max(axis=0).tolist()
        cross = (((x0, y0), (x1, y1)), ((x0, y1), (x1, y0)))
        items.append(Lines(cross, COLLISION_COLOR, 2 * width, BLOCK))
    return items
