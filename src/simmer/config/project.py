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

from typing import Literal

from pydantic import BaseModel, Field, field_validator

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
