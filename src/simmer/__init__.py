"""SimMeR, the Simulator for Mechatronics Robots.

The names below are imported on first use (PEP 562), so ``import simmer.client`` in a control
program does not load the simulator (NumPy, Numba, pydantic): a program pays only for the link.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

__version__ = "2.0.0.dev0"

_LAZY = {
    "ConfigError": "simmer.errors",
    "SimmerError": "simmer.errors",
    "SimConfig": "simmer.config",
    "load_config": "simmer.config",
    "Device": "simmer.devices",
    "DeviceParams": "simmer.devices",
    "register_device_kind": "simmer.devices",
    "Pose": "simmer.pose",
    "Simulation": "simmer.world",
}

if TYPE_CHECKING:
    from simmer.config import SimConfig, load_config
    from simmer.devices import Device, DeviceParams, register_device_kind
    from simmer.errors import ConfigError, SimmerError
    from simmer.pose import Pose
    from simmer.world import Simulation


def __getattr__(name: str) -> Any:
    """Import a public name from its module the first time it is used."""
    module = _LAZY.get(name)
    if module is None:
        raise AttributeError(f"module 'simmer' has no attribute {name!r}")
    value = getattr(importlib.import_module(module), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted([*globals(), *_LAZY])


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
