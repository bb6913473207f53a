"""A run's scenario: where the robot starts, where the block lies, which zone is the target.

Each part comes from the configuration's ``[scenario]`` table: taken from the configuration,
named outright, or drawn from the run's seed, each from its own stream (``scenario:start``,
``scenario:block``, ``scenario:target``), so drawing one never shifts another and the same seed
gives the same scenario in any process.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from simmer.config.maze import Maze, robot_outline
from simmer.config.models import Settings
from simmer.config.project import HEADINGS, Cell
from simmer.config.zones import Zones
from simmer.errors import ScenarioError
from simmer.geometry import (
    Pose,
    place_polygon,
    polygon_hits_grid,
    polygons_overlap,
    rectangle,
    wrap_degrees,
)

BLOCK_TRIES = 1000
"""Draws of a block place before giving up (a loading zone too small for the block)."""

Streams = Callable[[str], np.random.Generator]


@dataclass(frozen=True)
class Scenario:
    """One run's start pose, block centre and target zone (None: the maze has no drop-off
    zones)."""

    start: Pose
    block: tuple[float, float]
    target: str | None

    def describe(self) -> str:
        """One line: ``start [6, 42] heading 180; block [7.2, 9.1]; target B2``."""
        x, y, heading = self.start
        return (
            f"start [{x:g}, {y:g}] heading {heading:g}; block [{self.block[0]:.2f}, "
            f"{self.block[1]:.2f}]; target {self.target or 'none'}"
        )

    def as_dict(self) -> dict[str, object]:
        """Plain data (manifest, report)."""
        return {"start": list(self.start), "block": list(self.block), "target": self.target}


def parse_cell(text: str) -> tuple[Cell, float | None]:
    """``"row,col"`` or ``"row,col,heading"`` -> ((row, col), heading or None); ValueError."""
    parts = [p.strip() for p in text.split(",")]
    if len(parts) not in (2, 3):
        raise ValueError(
            f"{text!r} is not a cell: write 'row,col' or 'row,col,heading', e.g. '3,0,180'"
        )
    try:
        row, col = int(parts[0]), int(parts[1])
        heading = float(parts[2]) if len(parts) == 3 else None
    except ValueError:
        raise ValueError(
            f"{text!r} is not a cell: row and column are whole numbers, e.g. '3,0' or '3,0,180'"
        ) from None
    if heading is not None and not math.isfinite(heading):
        raise ValueError(f"{text!r}: the heading must be a finite number of degrees")
    return (row, col), heading


def parse_point(text: str) -> tuple[float, float]:
    """``"x,y"`` in inches -> (x, y); ValueError."""
    parts = text.split(",")
    try:
        x, y = (float(p) for p in parts)
    except ValueError:
        raise ValueError(f"{text!r} is not a place: write 'x,y' in inches, e.g. '6,6'") from None
    if not (math.isfinite(x) and math.isfinite(y)):
        raise ValueError(f"{text!r}: x and y must be finite numbers of inches")
    return x, y


def cell_centre(cell: Cell, size: float) -> tuple[float, float]:
    """The centre of a cell, inches."""
    return (cell[1] + 0.5) * size, (cell[0] + 0.5) * size


def robot_fits(settings: Settings, maze: Maze, x: float, y: float, heading: float) -> bool:
    """True if the robot's outline at this pose is clear of walls, solid cells and the edge."""
    outline = robot_outline(settings)
    placed = np.empty_like(outline)
    place_polygon(outline, x, y, heading, placed)
    return not polygon_hits_grid(placed, maze.hwall, maze.vwall, maze.solid, maze.cell)


def start_cells(settings: Settings, maze: Maze, zones: Zones, where: str) -> list[Cell]:
    """The cells a drawn start may use: the zones' start cells (``random``) or every open
    cell (``open``), keeping those where the robot fits at all four headings."""
    if where == "open":
        cells = [(int(r), int(c)) for r, c in zip(*np.nonzero(~maze.solid), strict=True)]
    else:
        cells = list(zones.start)
    return [
        cell
        for cell in cells
        if all(robot_fits(settings, maze, *cell_centre(cell, maze.cell), h) for h in HEADINGS)
    ]


def draw_scenario(settings: Settings, maze: Maze, zones: Zones, streams: Streams) -> Scenario:
    """The scenario the settings ask for, drawing from ``streams(name)`` where they say so.

    ScenarioError names a setting that cannot be met.
    """
    s = settings.scenario
    start = _start(settings, maze, zones, s.start, streams)
    block = _block(settings, maze, zones, s.block, start, streams)
    names = sorted(zones.dropoff)
    if s.target == "random":
        target = names[int(streams("scenario:target").integers(len(names)))] if names else None
    elif s.target in zones.dropoff:
        target = s.target
    else:
        known = ", ".join(names) or "none (this maze has no drop-off zones)"
        raise ScenarioError(
            "scenario.target", f"no drop-off zone {s.target!r}; the zones are {known}"
        )
    return Scenario(start, block, target)


def _start(settings: Settings, maze: Maze, zones: Zones, spec: str, streams: Streams) -> Pose:
    if spec == "config":
        return Pose(*settings.robot_start_position, wrap_degrees(settings.robot_start_rotation))
    if spec in ("random", "open"):
        cells = start_cells(settings, maze, zones, spec)
        if not cells:
            raise ScenarioError(
                "scenario.start",
                f"{spec!r} finds no start cell where the robot fits; name start "
                "cells in [zones] start, or use 'open'",
            )
        rng = streams("scenario:start")
        cell = cells[int(rng.integers(len(cells)))]
        return Pose(*cell_centre(cell, maze.cell), HEADINGS[int(rng.integers(len(HEADINGS)))])
    try:
        cell, heading = parse_cell(spec)
    except ValueError as exc:
        raise ScenarioError(
            "scenario.start",
            f"{exc}; or 'config', 'random' (a start cell) or 'open' (any open cell)",
        ) from None
    check_cell(maze, cell, "scenario.start")
    chosen = heading if heading is not None else settings.robot_start_rotation
    pose = Pose(*cell_centre(cell, maze.cell), wrap_degrees(chosen))
    if not robot_fits(settings, maze, *pose):
        raise ScenarioError(
            "scenario.start",
            f"the robot at cell {list(cell)} heading {pose.heading:g} "
            "overlaps a wall; choose a larger cell",
        )
    return pose


def check_cell(maze: Maze, cell: Cell, key: str) -> None:
    """ScenarioError unless ``cell`` is an open cell of the maze."""
    row, col = cell
    if not (0 <= row < maze.rows and 0 <= col < maze.cols):
        raise ScenarioError(
            key,
            f"cell [{row}, {col}] is outside the maze (rows 0-{maze.rows - 1}, "
            f"columns 0-{maze.cols - 1})",
        )
    if maze.solid[row, col]:
        raise ScenarioError(key, f"cell [{row}, {col}] is solid (0 in walls); choose an open cell")


def _block(
    settings: Settings,
    maze: Maze,
    zones: Zones,
    spec: str,
    start: Pose,
    streams: Streams,
) -> tuple[float, float]:
    if spec == "config":
        return settings.block_position
    robot = robot_outline(settings)
    placed_robot = np.empty_like(robot)
    place_polygon(robot, start.x, start.y, start.heading, placed_robot)
    size = settings.block_size
    square = rectangle(size, size)
    block = np.empty_like(square)

    def clear(x: float, y: float, clearance: float = 0.0) -> bool:
        if clearance:
            room = rectangle(size + 2 * clearance, size + 2 * clearance)
            place_polygon(room, x, y, settings.block_rotation, block)
            if polygon_hits_grid(block, maze.hwall, maze.vwall, maze.solid, maze.cell):
                return False
        place_polygon(square, x, y, settings.block_rotation, block)
        hits = polygon_hits_grid(block, maze.hwall, maze.vwall, maze.solid, maze.cell)
        return not hits and not polygons_overlap(block, placed_robot)

    if spec != "random":
        try:
            x, y = parse_point(spec)
        except ValueError as exc:
            raise ScenarioError("scenario.block", f"{exc}; or 'config' or 'random'") from None
        if not clear(x, y):
            raise ScenarioError(
                "scenario.block",
                f"the block at [{x:g}, {y:g}] overlaps a wall, a solid cell, the "
                "maze edge or the robot's start; put it inside an open cell",
            )
        return x, y
    if zones.loading is None:
        raise ScenarioError(
            "scenario.block",
            "'random' needs a loading zone: mark it with 3 cells (project "
            "convention) or name it in [zones] loading",
        )
    rng = streams("scenario:block")
    cells = zones.loading.cells
    clearance = settings.scenario.block_clearance
    for _ in range(BLOCK_TRIES):
        row, col = cells[int(rng.integers(len(cells)))]
        x = (col + float(rng.random())) * maze.cell
        y = (row + float(rng.random())) * maze.cell
        if clear(x, y, clearance):
            return x, y
    raise ScenarioError(
        "scenario.block",
        f"'random' finds no place in the loading zone {clearance:g} in clear of walls "
        f"(block_clearance) and clear of the robot after {BLOCK_TRIES} draws; make "
        "block_clearance or the block smaller, or the zone larger",
    )
