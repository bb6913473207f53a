"""A device kind of your own: a front bumper (a contact switch behind a bar).

This file is a worked example of the SimMeR device interface. A configuration loads it with
``plugins = ["devices/bumper.py"]`` (a path relative to the configuration file) and then uses
the kind by name::

    [sensors.b0]
    type = "bumper"
    position = [0, 4]
    width = 3

The bar is ``width`` inches wide across the device's heading; it reads 1 when a wall or the
block is within ``reach`` inches ahead of any point of it, else 0. A real switch can also
bounce or fail to close: ``miss`` is the chance that a press reads 0.
"""

from __future__ import annotations

import math

import numpy as np
from pydantic import Field

from simmer.devices import (
    Device,
    DeviceParams,
    Segment,
    Shape,
    Vec2,
    World,
    heading_vector,
    register_device_kind,
)

FEELERS = 5
"""Points along the bar that feel ahead (its two ends among them)."""


class BumperParams(DeviceParams):
    """The settings a configuration may give; every other key is an error, with a hint."""

    type: str = "bumper"
    width: float = Field(3.0, gt=0, description="Width of the bar, inches.")
    reach: float = Field(0.25, gt=0, description="How far ahead of the bar it feels, inches.")
    miss: float = Field(0.0, ge=0, le=1, description="Chance that a press reads 0.")


class Bumper(Device):
    """1 while the bar touches a wall or the block, else 0."""

    category = "sensor"
    Params = BumperParams

    def __init__(self, device_id: str, params: DeviceParams, rng: np.random.Generator) -> None:
        super().__init__(device_id, params, rng)  # first: it sets self.params, self.rng...
        self.pressed = False

    def bar(self, world: World) -> tuple[Vec2, Vec2, float]:
        """The bar's two ends in the world, and the heading it faces."""
        settings = self.params
        assert isinstance(settings, BumperParams)
        pose = self.world_pose(world.robot.pose)
        across = heading_vector(pose.heading - 90.0)  # along the bar
        half = settings.width / 2.0
        left = Vec2(pose.x - across.x * half, pose.y - across.y * half)
        right = Vec2(pose.x + across.x * half, pose.y + across.y * half)
        return left, right, pose.heading

    def simulate(self, value: float, world: World) -> float:
        """1.0 if any point of the bar is within ``reach`` of a wall or the block, else 0.0."""
        settings = self.params
        assert isinstance(settings, BumperParams)
        left, right, heading = self.bar(world)
        nearest = math.inf
        for k in range(FEELERS):
            t = k / (FEELERS - 1)
            x = left.x + (right.x - left.x) * t
            y = left.y + (right.y - left.y) * t
            nearest = min(
                nearest,
                world.maze.cast_ray(x, y, heading, settings.reach),
                world.block.cast_ray(x, y, heading),
            )
        self.pressed = nearest <= settings.reach
        # Every random draw comes from self.rng, so a seeded run repeats exactly.
        if self.pressed and settings.miss and self.rng.random() < settings.miss:
            return 0.0
        return 1.0 if self.pressed else 0.0

    def shapes(self, world: World) -> list[Shape]:
        """The bar: red while pressed at the last read, green otherwise."""
        left, right, _ = self.bar(world)
        return [Segment(left, right, (255, 0, 0) if self.pressed else (0, 160, 0))]


register_device_kind("bumper", Bumper)
