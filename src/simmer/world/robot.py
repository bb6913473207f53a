"""The robot: an outline, a pose, and the devices mounted on it (BEHAVIOUR §3-4)."""

from __future__ import annotations

import numpy as np

from simmer.devices import Device, Drive, Motor
from simmer.geometry import FloatArray, Pose, Vec2, place_polygon


class Robot:
    """A rigid outline at a pose, carrying motors, drives and sensors by id."""

    def __init__(self, outline: FloatArray, pose: Pose, height: float, devices: list[Device]):
        self.outline = outline
        self.start_pose = pose
        self.pose = pose
        self.turned = 0.0  # degrees turned during the last step (what a gyroscope senses)
        self.moved = Vec2(0.0, 0.0)  # robot-frame inches moved in the last step (an encoder's)
        self.height = height
        self.devices: dict[str, Device] = {device.id: device for device in devices}
        self.motors: dict[str, Motor] = {d.id: d for d in devices if isinstance(d, Motor)}
        self.drives: dict[str, Drive] = {d.id: d for d in devices if isinstance(d, Drive)}
        self.sensors: dict[str, Device] = {d.id: d for d in devices if d.category == "sensor"}
        self.updating: list[Device] = [d for d in devices if type(d).update is not Device.update]
        self.scratch = np.empty_like(outline)

    @property
    def any_drive_moving(self) -> bool:
        """True while any drive still has commanded motion left."""
        for drive in self.drives.values():  # noqa: SIM110 (a loop: any() builds a generator)
            if drive.remaining != 0.0:
                return True
        return False

    def stop(self) -> None:
        """Clear every drive's remaining motion."""
        for drive in self.drives.values():
            drive.stop()

    def polygon(self, pose: Pose | None = None) -> FloatArray:
        """The outline in the world frame at ``pose`` (default: the current pose)."""
        pose = pose or self.pose
        out = np.empty_like(self.outline)
        place_polygon(self.outline, pose.x, pose.y, pose.heading, out)
        return out

    def device_polygon(self, device: Device) -> FloatArray:
        """A device's outline in the world frame."""
        device_pose = device.world_pose(self.pose)
        out = np.empty_like(device.outline)
        place_polygon(device.outline, device_pose.x, device_pose.y, device_pose.heading, out)
        return out
