"""Typed, frozen configuration models.

The native file is TOML with SimMeR's own key names at the top level (so the lab manual's names
still apply: ``robot_start_position``, ``walls``, ``frame_rate``...) and one table per device::

    [sensors.u0]
    type = "ultrasonic"
    position = [0, 2.5]

The table name is the device id. Motors default to ``type = "motor"``, drives to
``type = "drive"``; sensors must say what they are.
"""

from __future__ import annotations

import codecs
from dataclasses import dataclass
from typing import Any, Literal

from pydantic import BaseModel, ConfigDict, Field, field_validator

from simmer.devices.base import Color, DeviceParams

Point = tuple[float, float]

SIMMER_DEFAULT_WALLS: tuple[tuple[int, ...], ...] = (
    (3, 3, 1, 1, 0, 2, 0, 2),
    (3, 3, 0, 1, 1, 1, 1, 1),
    (1, 0, 2, 0, 0, 1, 0, 1),
    (1, 1, 1, 1, 1, 1, 0, 2),
)

DEVICE_GROUPS: tuple[Literal["motors", "drives", "sensors"], ...] = ("motors", "drives", "sensors")


class Settings(BaseModel):
    """Every scalar setting of a configuration (BEHAVIOUR §8) plus SimMeR 2 additions."""

    model_config = ConfigDict(extra="forbid", frozen=True)

    # Control
    rand_error: bool = Field(False, description="True: fresh random noise every run.")
    rand_bias: bool = Field(False, description="True: draw each drive's bias once at start.")
    bias_strength: tuple[float, float] = Field(
        (0.02, 0.2),
        description="Standard deviations of the drawn bias: [linear, rotational].",
    )
    seed: int | None = Field(
        None, ge=0, description="Noise seed when rand_error is false (default: floor_seed)."
    )
    reply_bytes: Literal[4, 8] = Field(
        4, description="Reply width: 4 (float32, SimMeR 1.1, Arduino) or 8 (float64, SimMeR 1.0)."
    )
    plugins: tuple[str, ...] = Field(
        (), description="Python files or modules that register device kinds of your own."
    )
    # Network
    host: str = "127.0.0.1"
    port_rx: int = Field(61200, ge=1, le=65535)
    port_tx: int = Field(61201, ge=1, le=65535)
    timeout: float = Field(300.0, gt=0)
    str_encoding: str = "utf-8"
    # Block
    block_position: Point = (66.0, 5.0)
    block_rotation: float = 0.0
    block_size: float = Field(3.0, gt=0)
    # Robot
    robot_start_position: Point = (6.0, 42.0)
    robot_start_rotation: float = 180.0
    robot_width: float = Field(6.0, gt=0)
    robot_height: float = Field(6.0, gt=0)
    robot_outline: tuple[Point, ...] | None = Field(None, min_length=3)
    # Maze
    wall_segment_length: float = Field(12.0, gt=0)
    floor_segment_length: float = Field(3.0, gt=0)
    walls: tuple[tuple[int, ...], ...] = SIMMER_DEFAULT_WALLS
    floor_seed: int = Field(5489, ge=0, lt=2**32)
    # Graphics
    frame_rate: float = Field(60.0, gt=0, le=10000)
    ppi: float = Field(16.0, gt=0)
    border_pixels: int = Field(20, ge=0)
    background_color: Color = (43, 122, 120)
    wall_thickness: float = Field(0.25, ge=0)
    wall_color: Color = (255, 0, 0)
    robot_thickness: float = Field(0.25, ge=0)
    robot_color: Color = (0, 0, 255)
    block_thickness: float = Field(0.25, ge=0)
    block_color: Color = (127, 127, 20)
    # Debug
    simulate_list: tuple[str, ...] = ()

    @field_validator("bias_strength")
    @classmethod
    def _non_negative_strength(cls, value: tuple[float, float]) -> tuple[float, float]:
        if min(value) < 0:
            raise ValueError("both strengths must be 0 or more")
        return value

    @field_validator("str_encoding")
    @classmethod
    def _known_encoding(cls, value: str) -> str:
        try:
            codecs.lookup(value)
        except LookupError:
            raise ValueError(f"unknown text encoding {value!r}; use 'utf-8'") from None
        return value

    @field_validator("background_color", "wall_color", "robot_color", "block_color", mode="after")
    @classmethod
    def _rgb(cls, value: Color) -> Color:
        if any(not 0 <= c <= 255 for c in value):
            raise ValueError("each colour value must be between 0 and 255")
        return value


@dataclass(frozen=True)
class DeviceSpec:
    """One configured device: its id, table (group), registered kind and validated settings."""

    id: str
    group: Literal["motors", "drives", "sensors"]
    kind: str
    params: DeviceParams


@dataclass(frozen=True)
class SimConfig:
    """A whole validated configuration: settings plus devices, and where it came from."""

    settings: Settings
    devices: tuple[DeviceSpec, ...]
    source: str = "<built-in default>"

    def device(self, device_id: str) -> DeviceSpec:
        """The device with this id (KeyError if none)."""
        for spec in self.devices:
            if spec.id == device_id:
                return spec
        raise KeyError(device_id)

    def replace(self, **settings: Any) -> SimConfig:
        """A copy with some settings changed (re-validated), e.g. ``replace(rand_bias=True)``."""
        merged = self.settings.model_dump() | settings
        return SimConfig(Settings.model_validate(merged), self.devices, self.source)
