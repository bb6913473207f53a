"""Gripper: jaws at the front of the robot that pick the block up and put it down.

``g0-1`` closes the jaws: if the block's centre lies between them (``opening`` wide, ``depth``
deep, from the device's position forward along its heading, edges included), the robot holds
the block from then on. ``g0-0`` opens them and leaves the block where it is. Either command
answers whether the robot holds the block: 1.0 or 0.0 (SimMeR v1.2's framed text: ``True`` or
``False``, as it answers a drive).

A held block moves with the robot, counts in its outline for collisions (a move that would
push it into a wall is undone) and is seen by sensors as before, at its height. A block that is
not held is an obstacle, as in every SimMeR: the robot stops against it and never pushes it
(a pushed block would need friction and contact that no lab measured; the course's block is
picked up, not pushed).

The gripper lives among the drives (``[drives.g0]``): like a drive it acts rather than measures.
"""

from __future__ import annotations

from typing import ClassVar

import numpy as np
from pydantic import Field

from simmer.devices.base import Category, Color, Device, DeviceParams, Mount, World
from simmer.errors import CommandError
from simmer.geometry import rotate


class GripperParams(DeviceParams):
    """Gripper settings: where the jaws are and how large."""

    type: str = "gripper"
    position: Mount = Field(
        (0.0, 4.0), description="[x, y] of the middle of the jaws' back, robot frame, inches."
    )
    opening: float = Field(4.0, gt=0, description="Width between the open jaws, inches.")
    depth: float = Field(3.0, gt=0, description="Length of the jaws, inches.")
    color: Color = Field((90, 90, 90), description="RGB colour of the jaws' outline.")


class Gripper(Device):
    """Jaws that pick the block up (command 1) and put it down (0); both answer 1 if held."""

    category: ClassVar[Category] = "drive"
    Params = GripperParams

    def __init__(self, device_id: str, params: DeviceParams, rng: np.random.Generator) -> None:
        super().__init__(device_id, params, rng)
        assert isinstance(params, GripperParams)
        if params.outline is None:  # the space between the jaws
            half = params.opening / 2.0
            self.outline = np.array(
                [[-half, params.depth], [-half, 0.0], [half, 0.0], [half, params.depth]]
            )
        self.settings = params
        self.closed = False

    def between_jaws(self, world: World) -> bool:
        """True if the block's centre lies between the jaws (edges included)."""
        block = world.block
        pose = self.world_pose(world.robot.pose)
        local = rotate(block.x - pose.x, block.y - pose.y, -pose.heading)
        s = self.settings
        eps = 1e-9
        return abs(local.x) <= s.opening / 2.0 + eps and -eps <= local.y <= s.depth + eps

    def simulate(self, value: float, world: World) -> float:
        """Close (1) or open (0); 1.0 if the robot now holds the block, else 0.0."""
        block = world.block
        if value == 1.0:
            if not self.closed and self.between_jaws(world):
                block.hold(world.robot.pose)
            self.closed = True
        elif value == 0.0:
            if block.held is not None:
                block.release()
            self.closed = False
        else:
            raise CommandError(f"gripper {self.id}: 1 closes, 0 opens; not {value:g}")
        return 1.0 if block.held is not None else 0.0
