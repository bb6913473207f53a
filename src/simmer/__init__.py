"""SimMeR, the Simulator for Mechatronics Robots.

The names below are imported on first use (PEP 562), so ``import simmer.client`` in a control
program does not load the simulator (NumPy, Numba, pydantic): a program pays only for the link.

The public API is this package and the modules :mod:`simmer.client`, :mod:`simmer.devices`,
:mod:`simmer.ending`, :mod:`simmer.errors`, :mod:`simmer.pose`, :mod:`simmer.record`,
:mod:`simmer.sweep`, :mod:`simmer.batch` and :mod:`simmer.gym` (with the ``gym`` extra), each
with its names in ``__all__`` (docs/api.md). Every other module, and the modules inside those
packages, is internal and may change in any release
(``simmer._api`` lists them).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from simmer.lazy import lazy_names

__version__ = "2.0.0.dev0"
"""SimMeR's version (PEP 440), as a run folder's manifest and report record it."""

_LAZY = {
    "ConfigError": "simmer.errors",
    "SimmerError": "simmer.errors",
    "SimConfig": "simmer.config",
    "load_config": "simmer.config",
    "with_overrides": "simmer.config",
    "Device": "simmer.devices",
    "DeviceParams": "simmer.devices",
    "register_device_kind": "simmer.devices",
    "Pose": "simmer.pose",
    "Simulation": "simmer.world",
    "replay": "simmer.world.replay",
}

if TYPE_CHECKING:
    from simmer.config import SimConfig, load_config, with_overrides
    from simmer.devices import Device, DeviceParams, register_device_kind
    from simmer.errors import ConfigError, SimmerError
    from simmer.pose import Pose
    from simmer.world import Simulation
    from simmer.world.replay import replay


__getattr__, __dir__ = lazy_names(__name__, _LAZY, globals())

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
    "replay",
    "with_overrides",
]
