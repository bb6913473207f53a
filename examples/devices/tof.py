"""A device kind of your own: a time-of-flight distance sensor (like the VL53L0X).

This file is a worked example of the SimMeR device interface. A configuration loads it with
``plugins = ["devices/tof.py"]`` (a path relative to the configuration file) and then uses
the kind by name::

    [sensors.t0]
    type = "tof"
    position = [0, 4]

Unlike the ultrasonic sensor's wide cone, a time-of-flight sensor sends one narrow beam and has
a short range. Its reading is the distance in inches, or ``max_range`` if nothing is in reach.
"""

from __future__ import annotations

import math

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


class TimeOfFlightParams(DeviceParams):
    """The settings a configuration may give; every other key is an error, with a hint."""

    type: str = "tof"
    max_range: float = Field(47.0, gt=0, description="Longest reading, inches (1.2 m).")
    error: float = Field(0.015, ge=0, description="Percent error (SimMeR's definition).")
    sees_block: bool = Field(True, description="Whether the beam can hit the block.")


class TimeOfFlight(Device):
    """One narrow beam along the sensor's heading."""

    category = "sensor"
    Params = TimeOfFlightParams

    def simulate(self, value: float, world: World) -> float:
        """Distance in inches to the nearest wall (or block) straight ahead, with noise."""
        settings = self.params
        assert isinstance(settings, TimeOfFlightParams)
        pose = self.world_pose(world.robot.pose)
        distance = world.maze.cast_ray(pose.x, pose.y, pose.heading, settings.max_range)
        if settings.sees_block:
            distance = min(distance, world.block.cast_ray(pose.x, pose.y, pose.heading))
        if math.isinf(distance) or distance > settings.max_range:
            reading = settings.max_range
        else:
            # Noise must come from self.rng (via percent_error), so runs stay repeatable.
            reading = min(
                max(self.percent_error(distance, settings.error), 0.0), settings.max_range
            )
        self.last = (Vec2(pose.x, pose.y), pose.heading, reading, world.time)
        return reading

    def shapes(self, world: World) -> list[Shape]:
        """Draw the beam for half a second after each read."""
        last = getattr(self, "last", None)
        if last is None or world.time - last[3] > 0.5:
            return []
        origin, heading, reading, _ = last
        direction = heading_vector(heading)
        end = Vec2(origin.x + direction.x * reading, origin.y + direction.y * reading)
        return [Segment(origin, end, (255, 0, 255))]


register_device_kind("tof", TimeOfFlight)
