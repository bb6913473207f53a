"""Device kinds and their registry. Built-in kinds are registered on import."""

from simmer.devices.base import (
    Circle,
    Device,
    DeviceParams,
    Segment,
    Shape,
    World,
)
from simmer.devices.drive import Axes, Drive, DriveParams, Motion
from simmer.devices.motor import Motor, MotorParams
from simmer.devices.registry import (
    check_device_kind,
    device_kinds,
    get_device_kind,
    register_device_kind,
)
from simmer.devices.sensors import (
    Compass,
    CompassParams,
    Gyroscope,
    GyroscopeParams,
    Infrared,
    InfraredParams,
    Ultrasonic,
    UltrasonicParams,
)

register_device_kind("motor", Motor)
register_device_kind("drive", Drive)
register_device_kind("ultrasonic", Ultrasonic)
register_device_kind("gyroscope", Gyroscope)
register_device_kind("compass", Compass)
register_device_kind("infrared", Infrared)

# "simmer_device": a device class written for the original SimMeR (registers itself on import)
import simmer.compat.template  # noqa: E402, F401

__all__ = [
    "Axes",
    "Circle",
    "Compass",
    "CompassParams",
    "Device",
    "DeviceParams",
    "Drive",
    "DriveParams",
    "Gyroscope",
    "GyroscopeParams",
    "Infrared",
    "InfraredParams",
    "Motion",
    "Motor",
    "MotorParams",
    "Segment",
    "Shape",
    "Ultrasonic",
    "UltrasonicParams",
    "World",
    "check_device_kind",
    "device_kinds",
    "get_device_kind",
    "register_device_kind",
]
