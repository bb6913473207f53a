"""Settings of the course project: zones of the maze, the scenario a run draws, the score.

The ``walls`` codes give zones under a named convention (``[zones] convention``):

* ``"project"`` (the default): the 2024-25 project. The ``3`` cells are the loading zone, where
  the block starts; each ``2`` cell is a drop-off zone, named B1, B2... in reading order (top row
  first, left to right); a run may start in any other open cell.
* ``"lab2023"``: the 2023 lab manual's words. ``2`` marks where the block may be placed (the
  loading zone), ``3`` where the robot may start or drop the block: each connected group of
  ``3`` cells is one drop-off zone, named D1, D2... in reading order, and the start cells.
* ``"none"``: no zones from the codes.

A configuration may also name its zones outright (``loading``, ``dropoff``, ``start``), which
wins over the convention. Cells are written ``[row, column]``, row 0 on top, as in ``walls``.
"""

from __future__ import annotations

from typing import Any, Literal

from pydantic import BaseModel, Field, field_validator, model_validator

from simmer.devices.base import SETTINGS_CONFIG, Whole

Cell = tuple[Whole, Whole]
"""A maze cell, ``[row, column]`` (row 0 on top, as in ``walls``)."""
Convention = Literal["project", "lab2023", "none"]
HEADINGS = (0.0, 90.0, 180.0, 270.0)
"""The four headings a drawn start may have (degrees from +y)."""


class ZoneSettings(BaseModel):
    """Named areas of the maze: the loading zone, drop-off zones and start cells."""

    model_config = SETTINGS_CONFIG

    convention: Convention = Field(
        "project",
        description="Zones from the walls codes: 'project' (2024-25: loading zone = the 3 "
        "cells, drop-off zones B1.. = the 2 cells), 'lab2023' (the 2023 manual: block on a 2 "
        "cell, start or drop on a 3 cell) or 'none'.",
    )
    loading: tuple[Cell, ...] | None = Field(
        None, description="Loading-zone cells [[row, col], ...]; default: from the convention."
    )
    dropoff: dict[str, tuple[Cell, ...]] | None = Field(
        None,
        description="Drop-off zones by name, { B1 = [[0, 5]], ... }; default: from the convention.",
    )
    start: tuple[Cell, ...] | None = Field(
        None, description="Cells a drawn start may use; default: from the convention."
    )
    visible: bool | None = Field(
        None,
        description="Draw the zones on the floor; default: when the robot has a gripper "
        "(a project run), so Lab 1 pictures stay as they were.",
    )

    @field_validator("dropoff")
    @classmethod
    def _names(
        cls, value: dict[str, tuple[Cell, ...]] | None
    ) -> dict[str, tuple[Cell, ...]] | None:
        for name in value or {}:
            if not name or len(name) > 16 or not name.isascii() or not name.isalnum():
                raise ValueError(f"zone name {name!r} must be 1 to 16 letters or digits, like 'B1'")
        return value


class ScenarioSettings(BaseModel):
    """What a run draws from its seed (each from its own stream) or is told."""

    model_config = SETTINGS_CONFIG

    start: str = Field(
        "config",
        description="'config': robot_start_position and robot_start_rotation; 'random': a "
        "start cell and one of four headings drawn from the seed; 'open': any open cell; "
        "or a cell 'row,col' with an optional heading 'row,col,deg'.",
    )
    block: str = Field(
        "config",
        description="'config': block_position; 'random': a place inside the loading zone clear "
        "of walls, drawn from the seed; or 'x,y' in inches.",
    )
    block_clearance: float = Field(
        3.5,
        ge=0,
        description="A drawn block keeps this many inches between its sides and every wall, "
        "so a gripper can reach it and a robot turn beside it (the lab rover needs 3.5).",
    )
    target: str = Field(
        "random",
        description="The drop-off zone to deliver to: a zone's name, or 'random' (drawn).",
    )


class ScoreSettings(BaseModel):
    """The rubric a run is scored by: points per milestone, a penalty per collision."""

    model_config = SETTINGS_CONFIG

    entered_loading: float = Field(10.0, description="Points for entering the loading zone.")
    picked_up: float = Field(20.0, description="Points for picking the block up.")
    left_loading: float = Field(
        10.0, description="Points for leaving the loading zone holding the block."
    )
    delivered: float = Field(60.0, description="Points for delivering it to the target zone.")
    wrong_zone: float = Field(
        10.0, description="Points for delivering it to another drop-off zone instead."
    )
    collision: float = Field(-2.0, le=0, description="Points per collision (0 or less).")
    time_limit: float = Field(
        600.0, gt=0, description="Simulated seconds; a milestone after this earns nothing."
    )


MAX_GENERATED_SIDE = 200
"""Rows, and cells in a row, of a generated maze (the course's is 4 x 8): a 200 x 200 maze
and its ambiguity take about a second; larger ones can be drawn from smaller pieces."""
COURSE_ROWS, COURSE_COLS = 4, 8
Range = tuple[float, float]


class GenerateSettings(BaseModel):
    """The maze generator's knobs: a configuration's `[maze]` table, `simmer maze generate`'s flags.

    See :mod:`simmer.config.mazegen` for what each does."""

    model_config = SETTINGS_CONFIG

    seed: Whole = Field(0, ge=0, description="The maze's seed: the same seed, the same maze.")
    style: Literal["course", "perfect"] = Field(
        "course",
        description="'course': like the course's maze, with zones; 'perfect': a micromouse-"
        "like perfect maze (odd sizes, one way between any two cells, no zones).",
    )
    rows: Whole = Field(
        COURSE_ROWS, ge=2, le=MAX_GENERATED_SIDE, description="Rows of cells (course: 4)."
    )
    cols: Whole = Field(
        COURSE_COLS, ge=2, le=MAX_GENERATED_SIDE, description="Cells in a row (course: 8)."
    )
    cell: float = Field(12.0, ge=10.0, le=120.0, description="Side of a cell, inches.")
    loops: Range = Field(
        (0.0, 0.15),
        description="Share of loops: [least, most] independent loops per open cell "
        "(the course's maze has 0.04).",
    )
    dead_ends: Range = Field(
        (0.0, 1.0), description="[least, most] share of open cells that are dead ends."
    )
    ambiguity: Range = Field(
        (0.0, 1.0),
        description="[least, most] share of open cells that look like another to the sensors.",
    )
    tolerance: float = Field(
        1.0, ge=0.0, description="Inches within which two noise-free readings look alike."
    )
    dropoff: Whole = Field(4, ge=0, le=9, description="Single-cell drop-off zones (course: 4).")
    zone_gap: Whole = Field(
        2, ge=1, description="Cells (Manhattan) at least between any two zones' cells."
    )
    floor_seed: Whole | None = Field(
        None, ge=0, lt=2**32, description="Floor pattern seed; default: from the maze's seed."
    )

    @model_validator(mode="before")
    @classmethod
    def _perfect_size(cls, data: Any) -> Any:
        """A perfect maze's default size is odd: 5 x 9 (the course's 4 x 8, made odd)."""
        if isinstance(data, dict) and data.get("style") == "perfect":
            data = {"rows": COURSE_ROWS + 1, "cols": COURSE_COLS + 1, **data}
        return data

    @model_validator(mode="after")
    def _ranges(self) -> GenerateSettings:
        for name in ("loops", "dead_ends", "ambiguity"):
            low, high = getattr(self, name)
            if not 0.0 <= low <= high <= 1.0:
                raise ValueError(f"{name} must be [least, most] with 0 <= least <= most <= 1")
        if self.style == "perfect" and (self.rows % 2 == 0 or self.cols % 2 == 0):
            raise ValueError(
                f"a perfect maze has odd rows and columns (cells on the even ones, walls "
                f"between), not {self.rows} x {self.cols}; try rows = 5, cols = 9"
            )
        return self
