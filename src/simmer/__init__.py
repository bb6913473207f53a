"""SimMeR, the Simulator for Mechatronics Robots."""

from simmer.config import SimConfig, load_config
from simmer.devices import Device, DeviceParams, register_device_kind
from simmer.errors import ConfigError, SimmerError
from simmer.geometry import Pose
from simmer.world import Simulation

__version__ = "2.0.0.dev0"

__all__ = [
    "ConfigError",
    "Device",
    "DeviceParams",
    "Pose",
    "SimConfig",
    "SimmerError",
    "Simulation",
    "__version__",
    "load_config",
    "register_device_kind",
]
