"""Motor (SimMeR's ``MotorSimple``): a wheel whose reading is its odometer (BEHAVIOUR §5.1)."""

from __future__ import annotations

from typing import ClassVar

import numpy as np

from simmer.devices.base import Category, Device, DeviceParams, World
from simmer.geometry import FloatArray, rectangle


class MotorParams(DeviceParams):
    """A motor has only the common settings."""

    type: str = "motor"


class Motor(Device):
    """A wheel and motor. Reading = inches travelled by the wheel rim since the start."""

    category: ClassVar[Category] = "motor"
    Params = MotorParams
    default_outline: ClassVar[FloatArray] = rectangle(0.5, 2.0)

    def __init__(self, device_id: str, params: DeviceParams, rng: np.random.Generator) -> None:
        super().__init__(device_id, params, rng)
        self.odometer = 0.0

    def simulate(self, value: float, world: World) -> float:
        """Return the odometer; the command value is ignored."""
        return self.odometer
