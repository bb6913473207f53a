"""The time-of-flight ranger kind (``tof``): ST's VL53L0X and VL53L1X as presets.

A time-of-flight sensor times a laser pulse's return over a narrow cone. SimMeR casts
``num_rays`` rays across the cone (3 by default, against the ultrasonic fan's 7) with the
ultrasonic kind's kernel and reads the nearest return; the block is seen by the same height
rule. A preset and a ranging mode set the field of view, the longest range, the ranging error
and the value the real drivers return when nothing is in reach (docs/devices.md, "Built-in
sensors of the 2024-25 robots"); any of them may be set by hand instead.

Figures (ST datasheets DocID029104 and DocID031281; typical, white target, indoors; a
datasheet's "±N %" read as two standard deviations):

* ``vl53l0x``: 25° field of view; ``default``, ``high_accuracy`` and ``high_speed`` modes reach
  1.2 m, ``long_range`` 2 m; ±3 % (±5 % in ``high_speed`` and ``long_range``); nothing in reach
  reads 8190 (the millimetres Pololu's ``readRangeSingleMillimeters`` and ST's API report).
* ``vl53l1x``: 27° field of view; ``short`` 1.3 m, ``medium`` 2.9 m, ``long`` 3.6 m (in the
  dark); ±20 mm; nothing in reach reads -1 (Adafruit's ``distance()``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import ClassVar, Literal

import numpy as np
from pydantic import Field

from simmer.devices.base import Color, Device, DeviceParams, Segment, Shape, Whole, World
from simmer.geometry import FloatArray, Vec2, cast_fan, heading_vector, rectangle

MM_PER_INCH = 25.4


@dataclass(frozen=True)
class RangingMode:
    """One ranging mode of a preset: its reach and its error."""

    max_range_mm: float
    error: float
    """Standard deviation as a fraction of the distance."""
    error_mm: float
    """Standard deviation added whatever the distance, millimetres."""


@dataclass(frozen=True)
class TofPreset:
    """A real sensor's figures: field of view, its ranging modes and the no-return value."""

    fov: float
    modes: dict[str, RangingMode]
    default_mode: str
    out_of_range: float


PRESETS: dict[str, TofPreset] = {
    "vl53l0x": TofPreset(
        fov=25.0,
        modes={
            "default": RangingMode(1200.0, 0.015, 0.0),
            "high_accuracy": RangingMode(1200.0, 0.015, 0.0),
            "high_speed": RangingMode(1200.0, 0.025, 0.0),
            "long_range": RangingMode(2000.0, 0.025, 0.0),
        },
        default_mode="default",
        out_of_range=8190.0,
    ),
    "vl53l1x": TofPreset(
        fov=27.0,
        modes={
            "short": RangingMode(1300.0, 0.0, 10.0),
            "medium": RangingMode(2900.0, 0.0, 10.0),
            "long": RangingMode(3600.0, 0.0, 10.0),
        },
        default_mode="long",
        out_of_range=-1.0,
    ),
}
"""The presets by name (module docstring: where each figure comes from)."""


class TimeOfFlightParams(DeviceParams):
    """Time-of-flight ranger settings: a preset, its mode, and any figure set by hand."""

    type: str = "tof"
    preset: Literal["vl53l0x", "vl53l1x"] = Field(
        "vl53l0x", description="The sensor: 'vl53l0x' or 'vl53l1x' (docs/devices.md)."
    )
    mode: str | None = Field(
        None,
        description="Ranging mode: vl53l0x 'default', 'high_accuracy', 'high_speed', "
        "'long_range'; vl53l1x 'short', 'medium', 'long' (default 'long').",
    )
    fov: float | None = Field(
        None, gt=0, lt=180, description="Field of view in degrees; the preset's if unset."
    )
    max_range: float | None = Field(
        None, gt=0, description="Longest reading, inches; the mode's if unset."
    )
    error: float | None = Field(
        None, ge=0, description="Standard deviation as a fraction of the distance; the mode's."
    )
    error_constant: float | None = Field(
        None, ge=0, description="Standard deviation added at any distance, inches; the mode's."
    )
    out_of_range: float | None = Field(
        None,
        description="The reply when nothing is in reach (not converted by units); the "
        "preset's if unset (8190, -1).",
    )
    units: Literal["in", "mm"] = Field(
        "in", description="'in': inches as every SimMeR sensor; 'mm': whole millimetres."
    )
    num_rays: Whole = Field(3, ge=1, le=1000, description="Rays cast across the cone.")
    height: float | None = Field(
        None, gt=0, description="Mounting height in inches; defaults to the block size."
    )
    visible_measurement: bool = Field(True, description="Draw the beam after a read.")
    visible_measurement_time: float = Field(0.5, ge=0, description="How long, in seconds.")
    beam_color: Color = Field((255, 0, 255), description="RGB colour of the drawn beam.")

    def problems(self) -> list[tuple[str, str]]:
        """A mode the preset does not have, as a (key, message) pair."""
        modes = PRESETS[self.preset].modes
        if self.mode is not None and self.mode not in modes:
            names = ", ".join(f"'{m}'" for m in modes)
            return [("mode", f"{self.preset} has the ranging modes {names}, not {self.mode!r}")]
        return []

    def figures(self) -> tuple[float, float, float, float, float]:
        """(fov, max_range in, error, error_constant in, out_of_range): set or preset."""
        preset = PRESETS[self.preset]
        mode = preset.modes[self.mode or preset.default_mode]
        return (
            preset.fov if self.fov is None else self.fov,
            mode.max_range_mm / MM_PER_INCH if self.max_range is None else self.max_range,
            mode.error if self.error is None else self.error,
            mode.error_mm / MM_PER_INCH if self.error_constant is None else self.error_constant,
            preset.out_of_range if self.out_of_range is None else self.out_of_range,
        )

    def noise_keys(self) -> list[str]:
        """The noise settings in effect that are not zero (``simmer check``'s summary)."""
        _, _, error, constant, _ = self.figures()
        return [name for name, v in (("error", error), ("error_constant", constant)) if v]


class TimeOfFlight(Device):
    """Nearest return in a narrow cone; the driver's out-of-range value beyond reach."""

    Params = TimeOfFlightParams
    block_noise: ClassVar[bool] = True
    default_outline: ClassVar[FloatArray] = rectangle(1.0, 0.5)

    def __init__(self, device_id: str, params: DeviceParams, rng: np.random.Generator) -> None:
        super().__init__(device_id, params, rng)
        assert isinstance(params, TimeOfFlightParams)
        self.settings = params
        self.fov, self.max_range, self.error, self.error_constant, self.out_of_range = (
            params.figures()
        )
        self.rays = np.full(params.num_rays, math.inf)
        self.last_time = -math.inf
        self._last_x = self._last_y = 0.0
        self.last_heading = 0.0
        # the mounting height if set (None: the block's side, read at each read)
        self._height = params.height if params.height is not None else self.mount_height

    def height(self, world: World) -> float:
        """Mounting height: ``height``, else the third position value, else the block size."""
        return world.block.size if self._height is None else self._height

    def sees_block(self, world: World, x: float, y: float) -> bool:
        """The ultrasonic kind's rule with the field of view: ``atan(h / d) <= fov / 2``."""
        block = world.block
        h = self.height(world) - block.size
        d = math.hypot(block.x - x, block.y - y)
        return math.degrees(math.atan2(h, d)) <= self.fov / 2.0

    def distance(self, world: World) -> float:
        """The nearest return in inches, noise-free; inf if nothing is within ``max_range``."""
        # world_pose and sees_block written out, the same arithmetic in the same order: a
        # read's Python costs more than its three rays
        rx, ry, rheading = world.robot.pose
        px, py = self.position
        rad = math.radians(rheading)
        c, sn = math.cos(rad), math.sin(rad)
        x = rx + px * c - py * sn
        y = ry + px * sn + py * c
        heading = rheading + self.rotation
        maze, block = world.maze, world.block
        h = (block.size if self._height is None else self._height) - block.size
        d = math.hypot(block.x - x, block.y - y)
        nearest = cast_fan(
            maze.hwall,
            maze.vwall,
            maze.cell,
            maze.segments,
            block.segments,
            math.degrees(math.atan2(h, d)) <= self.fov / 2.0,
            x,
            y,
            heading,
            self.fov,
            self.max_range,
            self.rays,
        )
        self._last_x, self._last_y = x, y
        self.last_heading = heading
        return nearest

    @property
    def last_origin(self) -> Vec2:
        """Where the sensor was at its last read (built when the window asks)."""
        return Vec2(self._last_x, self._last_y)

    def simulate(self, value: float, world: World) -> float:
        """The distance with noise, in ``units``; ``out_of_range`` if nothing is in reach."""
        distance = self.distance(world)
        self.last_time = world.time
        if distance >= self.max_range:  # inf: no return within reach
            return self.out_of_range
        sd = self.error_constant + self.error * distance
        if sd > 0.0:  # rng.normal(0, sd) to the bit: an N(0, 2) draw of the block times sd / 2
            distance = max(distance + self.gauss() * (sd / 2.0), 0.0)
        return in_units(distance, self.settings.units)

    def shapes(self, world: World) -> list[Shape]:
        """The beam's rays of the last read, each to its return or the range, while recent."""
        s = self.settings
        if not s.visible_measurement or world.time - self.last_time > s.visible_measurement_time:
            return []
        n = s.num_rays
        origin = self.last_origin
        out: list[Shape] = []
        for k in range(n):
            length = min(float(self.rays[k]), self.max_range)
            direction = heading_vector(self.last_heading + ((k - (n - 1) / 2.0) / n) * self.fov)
            end = Vec2(origin.x + direction.x * length, origin.y + direction.y * length)
            out.append(Segment(origin, end, s.beam_color))
        return out


def in_units(inches: float, units: str) -> float:
    """A distance in inches as the sensor replies: inches, or whole millimetres."""
    return float(round(inches * MM_PER_INCH)) if units == "mm" else inches
