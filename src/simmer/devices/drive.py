"""Drive: an abstract device that moves or turns the robot over several steps (BEHAVIOUR §5.2).

``w0-5`` moves 5 in along the drive's velocity (or turns 5° for a rotational drive). The
command is refused with NaN while any drive of the robot is moving and accepted with +inf.
Each step the drive advances by at most ``speed / frame_rate``; the motion carries the drive's
bias, and the motors' odometers advance even if a collision undoes the motion.

A drive with both ``velocity`` and ``ang_velocity`` (which only an original ``config.py`` may
have, BEHAVIOUR §6.3) moves as the original did: its speed is ``|velocity| + |ang_velocity|``
units per second, and each unit moves the robot 1 in along the velocity and turns it 1 degree
clockwise, so the robot follows an arc.
"""

from __future__ import annotations

import math
from typing import ClassVar, NamedTuple

import numpy as np
from pydantic import BaseModel, Field

from simmer.devices.base import SETTINGS_CONFIG, Category, Device, DeviceParams, World
from simmer.devices.motor import Motor
from simmer.errors import CommandError


class Axes(BaseModel):
    """A value along robot x, robot y and rotation (used for drive bias and error)."""

    model_config = SETTINGS_CONFIG

    x: float = 0.0
    y: float = 0.0
    rotation: float = 0.0


class DriveParams(DeviceParams):
    """Drive settings: exactly one of ``velocity`` / ``ang_velocity`` is non-zero (an original
    ``config.py`` may set both: an arc, see the module docstring)."""

    type: str = "drive"
    visible: bool = False
    velocity: tuple[float, float] = Field(
        (0.0, 0.0), description="Translation speed [vx, vy] in in/s, robot frame."
    )
    ang_velocity: float = Field(0.0, description="Rotation speed in deg/s (clockwise positive).")
    motors: tuple[str, ...] = Field((), description="Ids of the motors this drive turns.")
    motor_direction: tuple[float, ...] = Field(
        (), description="+1 or -1 for each motor (multiplies its odometer)."
    )
    bias: Axes = Field(Axes(), description="Systematic extra motion per unit commanded.")
    error: Axes = Field(Axes(), description="Percent error of the commanded amount.")

    def problems(self) -> list[tuple[str, str]]:
        """Mistakes that would stop the drive working at all, as (key, message) pairs."""
        found: list[tuple[str, str]] = []
        if self.velocity == (0.0, 0.0) and self.ang_velocity == 0.0:
            found.append(
                ("velocity", "the drive never moves: give a non-zero velocity or ang_velocity")
            )
        if len(self.motors) != len(self.motor_direction):
            found.append(
                (
                    "motor_direction",
                    f"has {len(self.motor_direction)} entries but motors has "
                    f"{len(self.motors)}; give one direction (+1 or -1) per motor",
                )
            )
        return found

    def strict_problems(self) -> list[tuple[str, str]]:
        """Settings the original SimMeR ran (an arc drive, an omni wheel's direction) but a
        native configuration may not have, as (key, message) pairs."""
        found: list[tuple[str, str]] = []
        if self.velocity != (0.0, 0.0) and self.ang_velocity != 0.0:
            found.append(
                (
                    "ang_velocity",
                    "a drive either translates (velocity) or rotates (ang_velocity), never both; "
                    "with both, each unit commanded moves the robot 1 in along velocity and "
                    "turns it 1 degree (an arc); make two drives, or set one of them to 0",
                )
            )
        for i, direction in enumerate(self.motor_direction):
            if direction not in (1.0, -1.0):
                found.append(
                    (
                        f"motor_direction[{i}]",
                        f"must be 1 or -1, not {direction:g}; another value multiplies the "
                        "motor's odometer (as for an omni wheel)",
                    )
                )
        return found


class Motion(NamedTuple):
    """One step of commanded motion in the robot frame, plus the amount it used up (a
    named tuple: one is built every step a drive moves, a third of a frozen dataclass's cost)."""

    dx: float
    dy: float
    rotation: float
    step: float


class Drive(Device):
    """Moves the robot along ``velocity``, turns it at ``ang_velocity``, or both (an arc)."""

    category: ClassVar[Category] = "drive"
    block_noise: ClassVar[bool] = True
    Params = DriveParams

    def __init__(self, device_id: str, params: DeviceParams, rng: np.random.Generator) -> None:
        super().__init__(device_id, params, rng)
        assert isinstance(params, DriveParams)
        self.settings = params
        self.bias = params.bias
        linear = math.hypot(*params.velocity)
        self.rotational = linear == 0.0  # only turns: its amounts are degrees
        # per unit commanded: inches along the velocity (robot frame) and degrees turned
        self.unit = (
            (params.velocity[0] / linear, params.velocity[1] / linear) if linear else (0.0, 0.0)
        )
        self.turn = 1.0 if params.ang_velocity != 0.0 else 0.0
        self.speed = linear + abs(params.ang_velocity)  # units per second
        self.motors: list[Motor] = []
        self.gains: list[float] = []
        self.remaining = 0.0

    def bind_motors(self, motors: list[Motor]) -> None:
        """Attach the motor devices named in the configuration and work out odometer gains."""
        self.motors = motors
        self.gains = [
            self._odometer_gain(motor, direction)
            for motor, direction in zip(motors, self.settings.motor_direction, strict=True)
        ]

    def _odometer_gain(self, motor: Motor, direction: float) -> float:
        """Inches of wheel travel per unit of drive travel (BEHAVIOUR §5.2)."""
        rad = math.radians(motor.rotation)
        pointing = (-math.sin(rad), math.cos(rad))
        if self.rotational:
            px, py = motor.position
            radius = math.hypot(px, py)
            if radius == 0.0:
                return 0.0
            tangent = (-py / radius, px / radius)
            cos_a = abs(tangent[0] * pointing[0] + tangent[1] * pointing[1])
            scale = 2.0 * math.pi * radius / 360.0
        else:
            cos_a = abs(self.unit[0] * pointing[0] + self.unit[1] * pointing[1])
            scale = 1.0
        if cos_a < 1e-12:
            return 0.0
        return scale * direction / cos_a

    def set_bias(self, bias: Axes) -> None:
        """Replace the bias (used when ``rand_bias`` draws one at start)."""
        self.bias = bias

    def simulate(self, value: float, world: World) -> float:
        """Start moving by ``value`` (in or deg): +inf if accepted, NaN if a drive is busy."""
        if not math.isfinite(value):
            raise CommandError(f"drive {self.id}: {value!r} is not a distance")
        if world.robot.any_drive_moving:
            return math.nan
        error = self.settings.error
        error_total = self.unit[0] * error.x + self.unit[1] * error.y + self.turn * error.rotation
        self.remaining = self.percent_error(value, error_total)
        return math.inf

    def stop(self) -> None:
        """Clear any remaining motion (the ``xx`` emergency stop)."""
        self.remaining = 0.0

    def advance(self, dt: float) -> Motion:
        """Use up one step of the remaining motion, turn the motors, return the motion."""
        limit = self.speed * dt
        step = math.copysign(min(abs(self.remaining), limit), self.remaining)
        self.remaining -= step
        if abs(self.remaining) < 1e-12:
            self.remaining = 0.0
        for motor, gain in zip(self.motors, self.gains, strict=True):
            motor.odometer += step * gain
        bias = self.bias
        return Motion(
            dx=(self.unit[0] + bias.x) * step,
            dy=(self.unit[1] + bias.y) * step,
            rotation=(self.turn + bias.rotation) * step,
            step=step,
        )
