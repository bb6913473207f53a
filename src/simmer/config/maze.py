"""The maze (walls and floor pattern) and the block (BEHAVIOUR §2-3), as a configuration
describes them. Here, with the configuration, because validating one needs the geometry (a
robot or block placed in a wall, a zone on a solid cell); the world steps the same objects."""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from functools import cached_property

import numpy as np

from simmer.config.models import Settings
from simmer.geometry import (
    BoolArray,
    FloatArray,
    Pose,
    heading_vector,
    place_polygon,
    ray_grid,
    ray_segments,
    rectangle,
    rotate,
)


def floor_tiles(cols: int, rows: int, cell: float, tile: float) -> tuple[float, float]:
    """Tiles across and down the floor, as SimMeR counts them: a part tile counts, but rounding
    to 9 decimals first keeps 96 / 3 at 32. Floats, since an absurd size gives an absurd count
    (even infinity), which the configuration check refuses before anything is allocated."""
    across, down = cols * cell / tile, rows * cell / tile
    if not (math.isfinite(across) and math.isfinite(down)):
        return across, down
    return float(math.ceil(round(across, 9))), float(math.ceil(round(down, 9)))


def floor_pattern(cols: int, rows: int, cell: float, tile: float, seed: int) -> BoolArray:
    """SimMeR's floor: True = white, indexed [row, column] of tiles.

    Bit-identical to the original (and so to the painted lab maze): NumPy's legacy Mersenne
    Twister seeded with ``seed`` draws ``n_x · n_y`` values; tile (ix, iy) takes draw
    ``ix · n_y + iy`` and is white when it is at least 0.5.
    """
    across, down = floor_tiles(cols, rows, cell, tile)
    n_x, n_y = int(across), int(down)
    draws = np.random.RandomState(seed).random(n_x * n_y)
    result: BoolArray = (draws.reshape(n_x, n_y) >= 0.5).T.copy()
    return result


@dataclass
class Maze:
    """Walls on a grid of square cells, and the floor tiles.

    ``solid[r, c]`` is True for blocked cells. ``hwall[r, c]`` marks a wall on the horizontal
    grid line y = r·cell over column c; ``vwall[r, c]`` one on the vertical line x = c·cell over
    row r. An edge is a wall on the outer boundary, or between a solid and an open cell.
    """

    cells: tuple[tuple[int, ...], ...]
    cell: float
    tile: float
    floor_seed: int
    solid: BoolArray = field(init=False)
    hwall: BoolArray = field(init=False)
    vwall: BoolArray = field(init=False)

    def __post_init__(self) -> None:
        # Compared in Python: any other whole number is floor, however large (2**64 is too).
        self.solid = np.array([[cell == 0 for cell in row] for row in self.cells], dtype=bool)
        rows, cols = self.solid.shape
        padded = np.pad(self.solid, 1, constant_values=True)
        self.hwall = padded[:-1, 1:-1] != padded[1:, 1:-1]
        self.vwall = padded[1:-1, :-1] != padded[1:-1, 1:]
        self.hwall[0, :] = True
        self.hwall[rows, :] = True
        self.vwall[:, 0] = True
        self.vwall[:, cols] = True

    @cached_property
    def segments(self) -> FloatArray:
        """The walls as segments (N, 4: x1, y1, x2, y2), collinear touching pieces merged
        (made when first asked: checking a maze file's cells needs only the grid)."""
        return _merged_segments(self.hwall, self.vwall, self.cell)

    @cached_property
    def floor_white(self) -> BoolArray:
        """Which floor tiles are white (:func:`floor_pattern`; made when first asked)."""
        return floor_pattern(self.cols, self.rows, self.cell, self.tile, self.floor_seed)

    @classmethod
    def from_settings(cls, settings: Settings) -> Maze:
        """Build the maze a configuration describes."""
        return cls(
            settings.walls,
            settings.wall_segment_length,
            settings.floor_segment_length,
            settings.floor_seed,
        )

    @property
    def rows(self) -> int:
        """Number of cell rows."""
        return int(self.solid.shape[0])

    @property
    def cols(self) -> int:
        """Number of cell columns."""
        return int(self.solid.shape[1])

    @property
    def width(self) -> float:
        """Maze width in inches."""
        return self.cols * self.cell

    @property
    def height(self) -> float:
        """Maze height in inches."""
        return self.rows * self.cell

    def open_cell_centre(self) -> list[float]:
        """Centre of the first open cell (for error-message suggestions)."""
        rows, cols = np.nonzero(~self.solid)
        return [(int(cols[0]) + 0.5) * self.cell, (int(rows[0]) + 0.5) * self.cell]

    def cast_ray(self, x: float, y: float, heading: float, limit: float = math.inf) -> float:
        """Distance from (x, y) along ``heading`` to the first wall (inf if beyond ``limit``)."""
        direction = heading_vector(heading)
        distance = float(ray_grid(self.hwall, self.vwall, self.cell, x, y, *direction, limit))
        if distance < 0.0:  # outside the grid: test every wall segment
            distance = float(ray_segments(x, y, *direction, self.segments))
        return distance if distance <= limit else math.inf


def _merged_segments(hwall: BoolArray, vwall: BoolArray, cell: float) -> FloatArray:
    """Wall segments (N, 4: x1, y1, x2, y2), collinear touching pieces merged."""
    segments: list[tuple[float, float, float, float]] = []
    for r, line in enumerate(hwall):
        for start, stop in _runs(line):
            segments.append((start * cell, r * cell, stop * cell, r * cell))
    for c, line in enumerate(vwall.T):
        for start, stop in _runs(line):
            segments.append((c * cell, start * cell, c * cell, stop * cell))
    return np.array(segments, dtype=np.float64).reshape(-1, 4)


def _runs(line: BoolArray) -> list[tuple[int, int]]:
    """[start, stop) index pairs of the runs of True in a boolean line."""
    padded = np.concatenate(([False], line, [False])).astype(np.int8)
    edges = np.flatnonzero(np.diff(padded))
    return list(zip(edges[::2].tolist(), edges[1::2].tolist(), strict=True))


@dataclass
class Block:
    """The cube the robot must find: centre, rotation (degrees from +y) and side."""

    x: float
    y: float
    rotation: float
    size: float
    polygon: FloatArray = field(init=False)
    segments: FloatArray = field(init=False)
    held: Pose | None = field(init=False, default=None)
    """While a gripper holds the block: its pose in the robot's frame (it moves with the robot)."""

    def __post_init__(self) -> None:
        self.place(self.x, self.y, self.rotation)

    @classmethod
    def from_settings(cls, settings: Settings) -> Block:
        """The block a configuration describes."""
        x, y = settings.block_position
        return cls(x, y, settings.block_rotation, settings.block_size)

    @property
    def local(self) -> FloatArray:
        """The block's outline in its own frame."""
        return rectangle(self.size, self.size)

    def place(self, x: float, y: float, rotation: float) -> None:
        """Move the block (keeps its outline and edge segments in step)."""
        self.x, self.y, self.rotation = x, y, rotation
        self.polygon = np.empty((4, 2))
        place_polygon(self.local, x, y, rotation, self.polygon)
        self.segments = np.hstack((self.polygon, np.roll(self.polygon, -1, axis=0)))

    def carry_to(self, pose: Pose, polygon: FloatArray) -> None:
        """Move the held block to ``pose`` whose outline, already placed, is ``polygon``
        (each step of a carried block: no new arrays)."""
        self.x, self.y, self.rotation = pose
        self.polygon[:] = polygon
        self.segments[:, :2] = polygon
        self.segments[:-1, 2:] = polygon[1:]
        self.segments[-1, 2:] = polygon[0]

    def hold(self, robot: Pose) -> None:
        """A gripper took the block: from now on it keeps its pose relative to the robot."""
        local = rotate(self.x - robot.x, self.y - robot.y, -robot.heading)
        self.held = Pose(local.x, local.y, self.rotation - robot.heading)

    def release(self) -> None:
        """The gripper let go: the block stays where it is."""
        self.held = None

    def carried_pose(self, robot: Pose) -> Pose:
        """Where the held block is when the robot is at ``robot``."""
        assert self.held is not None
        offset = rotate(self.held.x, self.held.y, robot.heading)
        return Pose(robot.x + offset.x, robot.y + offset.y, self.held.heading + robot.heading)

    def cast_ray(self, x: float, y: float, heading: float) -> float:
        """Distance from (x, y) along ``heading`` to the block's outline; inf if it misses."""
        return float(ray_segments(x, y, *heading_vector(heading), self.segments))


def robot_outline(settings: Settings) -> FloatArray:
    """The robot's outline in its own frame: ``robot_outline``, or a square of ``robot_width``."""
    if settings.robot_outline is not None:
        return np.asarray(settings.robot_outline, dtype=np.float64)
    return rectangle(settings.robot_width, settings.robot_width)
