"""Device kinds and their registry (built-in kinds are imported on first use, by name).

What a device kind of one's own subclasses (:class:`Device`, :class:`DeviceParams`), the world
it sees (:class:`World`, its :class:`Shape` parts, :class:`Vec2`, :func:`heading_vector`) and
how it is registered; docs/devices.md walks through one.
"""

from simmer.devices.base import (
    Circle,
    Device,
    DeviceParams,
    Segment,
    Shape,
    World,
)
from simmer.devices.drive import Axes, Drive, DriveParams, Motion
from simmer.devices.lidar import Lidar, LidarParams
from simmer.devices.motion import Encoder, EncoderParams, Imu, ImuParams
from simmer.devices.motor import Motor, MotorParams
from simmer.devices.registry import (
    DeviceKinds,
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
from simmer.devices.tof import TimeOfFlight, TimeOfFlightParams
from simmer.geometry import heading_vector
from simmer.pose import Vec2

__all__ = [
    "Axes",
    "Circle",
    "Compass",
    "CompassParams",
    "Device",
    "DeviceKinds",
    "DeviceParams",
    "Drive",
    "DriveParams",
    "Encoder",
    "EncoderParams",
    "Gyroscope",
    "GyroscopeParams",
    "Imu",
    "ImuParams",
    "Infrared",
    "InfraredParams",
    "Lidar",
    "LidarParams",
    "Motion",
    "Motor",
    "MotorParams",
    "Segment",
    "Shape",
    "TimeOfFlight",
    "TimeOfFlightParams",
    "Ultrasonic",
    "UltrasonicParams",
    "Vec2",
    "World",
    "check_device_kind",
    "device_kinds",
    "get_device_kind",
    "heading_vector",
    "register_device_kind",
]
