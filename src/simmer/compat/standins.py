"""Stand-ins for the modules a SimMeR ``config.py`` and its device files import.

A SimMeR configuration does ``import pygame.math as pm`` and ``from devices.motors import
MotorSimple``; a user's device (copied from ``devices/template.py``) does ``from devices.device
import Device``, ``import config as CONFIG`` and ``import utilities``. :class:`StandIns` puts small
replacements for those names in :data:`sys.modules` only while such a file runs, and afterwards
removes every module it added (and anything imported from the configuration's folder), so
nothing leaks into the rest of the process and pygame is never needed.

The stand-in device classes do nothing but remember the information dictionary they were built
from; :func:`captured_info` gives it back. The stand-in ``utilities`` module offers every public
helper of the original's, from :mod:`simmer.compat.utilities`.
"""

from __future__ import annotations

import math
import sys
import types
from collections.abc import Iterator, Sequence
from pathlib import Path
from typing import Any

from simmer.compat import utilities

# ----------------------------------------------------------------------------- pygame.math


class Vector2:
    """Enough of ``pygame.math.Vector2`` for configurations and template devices."""

    __slots__ = ("x", "y")

    def __init__(self, x: Any = 0.0, y: float | None = None) -> None:
        if y is None and isinstance(x, Sequence | Vector2):
            x, y = x[0], x[1]
        self.x = float(x)
        self.y = float(y if y is not None else x)

    def __iter__(self) -> Iterator[float]:
        return iter((self.x, self.y))

    def __len__(self) -> int:
        return 2

    def __getitem__(self, index: int) -> float:
        return (self.x, self.y)[index]

    def __repr__(self) -> str:
        return f"Vector2({self.x:g}, {self.y:g})"

    def __eq__(self, other: object) -> bool:
        if isinstance(other, Vector2 | Sequence) and len(other) == 2:
            return self.x == other[0] and self.y == other[1]
        return NotImplemented

    def __hash__(self) -> int:
        return hash((self.x, self.y))

    def __add__(self, other: Any) -> Vector2:
        return Vector2(self.x + other[0], self.y + other[1])

    __radd__ = __add__

    def __sub__(self, other: Any) -> Vector2:
        return Vector2(self.x - other[0], self.y - other[1])

    def __rsub__(self, other: Any) -> Vector2:
        return Vector2(other[0] - self.x, other[1] - self.y)

    def __mul__(self, other: Any) -> Any:
        if isinstance(other, Vector2):
            return self.dot(other)
        return Vector2(self.x * other, self.y * other)

    __rmul__ = __mul__

    def __truediv__(self, other: float) -> Vector2:
        return Vector2(self.x / other, self.y / other)

    def __neg__(self) -> Vector2:
        return Vector2(-self.x, -self.y)

    def dot(self, other: Any) -> float:
        """Dot product."""
        return float(self.x * other[0] + self.y * other[1])

    def length(self) -> float:
        """Euclidean length."""
        return math.hypot(self.x, self.y)

    magnitude = length

    def length_squared(self) -> float:
        """Squared length."""
        return self.x * self.x + self.y * self.y

    magnitude_squared = length_squared

    def distance_to(self, other: Any) -> float:
        """Distance to another point."""
        return math.hypot(self.x - other[0], self.y - other[1])

    def normalize(self) -> Vector2:
        """Unit vector in the same direction."""
        size = self.length()
        return Vector2(self.x / size, self.y / size)

    def rotate(self, angle: float) -> Vector2:
        """Rotated by ``angle`` degrees (pygame's sense: +x towards +y, clockwise on screen)."""
        rad = math.radians(angle)
        c, s = math.cos(rad), math.sin(rad)
        return Vector2(self.x * c - self.y * s, self.x * s + self.y * c)

    def copy(self) -> Vector2:
        """A copy."""
        return Vector2(self.x, self.y)


# ----------------------------------------------------------------------------- devices


class StandInDevice:
    """``devices.device.Device``: remembers how it was built; user devices subclass it."""

    _simmer_args: tuple[Any, ...]

    def __new__(cls, *args: Any, **kwargs: Any) -> StandInDevice:
        """Record the constructor's arguments, whatever the subclass's ``__init__`` does."""
        instance = super().__new__(cls)
        instance._simmer_args = args + tuple(kwargs.values())
        return instance

    def __init__(self, d_id: str, position: Any, rotation: float, visible: bool) -> None:
        self.id = d_id
        self.position = Vector2(position[0], position[1])
        self.rotation = float(rotation)
        self.visible = visible
        self.d_type = ""
        self.name = ""
        self.outline = [Vector2(-0.5, -0.5), Vector2(0, 1), Vector2(0.5, -0.5)]
        self.color = (0, 0, 255)
        self.outline_thickness = 0.25
        self.position_global = self.position.copy()
        self.rotation_global = self.rotation


class _BuiltIn(StandInDevice):
    """A stand-in for one of SimMeR's own device classes, built from an info dictionary."""

    group = ""
    kind = ""

    def __init__(self, info: Any = None, *args: Any) -> None:
        data = info if isinstance(info, dict) else {}
        super().__init__(
            data.get("id", ""), data.get("position", (0, 0)), data.get("rotation", 0), True
        )
        self.d_type = self.group[:-1]


def _builtin(name: str, group: str, kind: str) -> type[_BuiltIn]:
    return type(name, (_BuiltIn,), {"group": group, "kind": kind, "__module__": __name__})


BUILTIN_CLASSES: dict[str, tuple[str, type[_BuiltIn]]] = {
    "motors": ("MotorSimple", _builtin("MotorSimple", "motors", "motor")),
    "drive": ("Drive", _builtin("Drive", "drives", "drive")),
    "ultrasonic": ("Ultrasonic", _builtin("Ultrasonic", "sensors", "ultrasonic")),
    "gyroscope": ("Gyroscope", _builtin("Gyroscope", "sensors", "gyroscope")),
    "compass": ("Compass", _builtin("Compass", "sensors", "compass")),
    "infrared": ("Infrared", _builtin("Infrared", "sensors", "infrared")),
}
"""SimMeR module name under ``devices`` -> (class name, stand-in class)."""


def builtin_kind(obj: object) -> str | None:
    """The SimMeR 2 kind of a stand-in built-in device ('motor', 'ultrasonic'...), else None."""
    return type(obj).kind if isinstance(obj, _BuiltIn) else None


def captured_info(obj: StandInDevice) -> dict[str, Any]:
    """The information dictionary a device was built from (or its four positional values)."""
    args = obj._simmer_args
    if len(args) == 1 and isinstance(args[0], dict):
        return dict(args[0])
    names = ("id", "position", "rotation", "visible")
    return dict(zip(names, args, strict=False))


# ----------------------------------------------------------------------------- utilities


def _missing(module: str, provided: str) -> Any:
    def missing(name: str) -> Any:
        raise AttributeError(
            f"SimMeR 2 provides only {provided} from {module!r}, not {name!r}; a device that "
            "needs more should become a SimMeR 2 device kind (see docs/migrating.md)"
        )

    return missing


UTILITIES = types.ModuleType("utilities", "SimMeR 2 stand-in for SimMeR's utilities module.")
UTILITIES.__dict__.update({name: getattr(utilities, name) for name in utilities.__all__})
UTILITIES.__getattr__ = _missing(  # type: ignore[method-assign]
    "utilities", "SimMeR's public helpers (" + ", ".join(utilities.__all__) + ")"
)


def _module(name: str, **attrs: Any) -> types.ModuleType:
    module = types.ModuleType(name)
    module.__dict__.update(attrs)
    return module


# ----------------------------------------------------------------------------- the context


class StandIns:
    """Provide SimMeR's module names while ``with StandIns(...):`` runs, then remove them.

    ``device_dirs`` are the folders searched for the user's own ``devices.<name>`` modules;
    ``config`` is the module a device's ``import config as CONFIG`` (or ``config.config``) gets.
    """

    OWN_NAMES = ("pygame", "devices", "config", "utilities")

    def __init__(self, base_dir: Path, device_dirs: list[Path], config: types.ModuleType) -> None:
        self.base_dir = base_dir.resolve()
        self.device_dirs = [d.resolve() for d in device_dirs]
        self.config = config
        self.user_modules: dict[str, types.ModuleType] = {}
        self._saved: dict[str, types.ModuleType] = {}
        self._before: set[str] = set()
        self._path: list[str] = []

    def _modules(self) -> dict[str, types.ModuleType]:
        pm = _module("pygame.math", Vector2=Vector2)
        pygame = _module("pygame", math=pm, Vector2=Vector2, __path__=[])
        pygame.__getattr__ = _missing("pygame", "pygame.math.Vector2")  # type: ignore[method-assign]
        device = _module("devices.device", Device=StandInDevice)
        devices = _module("devices", device=device, __path__=[str(d) for d in self.device_dirs])
        found = {"pygame": pygame, "pygame.math": pm, "devices": devices}
        found["devices.device"] = device
        for module_name, (class_name, cls) in BUILTIN_CLASSES.items():
            module = _module(f"devices.{module_name}", **{class_name: cls})
            setattr(devices, module_name, module)
            found[f"devices.{module_name}"] = module
        self.config.__dict__.setdefault("config", self.config)
        self.config.__dict__.setdefault("__path__", [])
        found["config"] = self.config
        found["config.config"] = self.config
        found["utilities"] = UTILITIES
        return found

    def _own_name(self, name: str) -> bool:
        return name.split(".", 1)[0] in self.OWN_NAMES

    def _from_user_folder(self, module: object) -> bool:
        file = getattr(module, "__file__", None)
        roots = [self.base_dir, *(d.parent for d in self.device_dirs)]
        return file is not None and any(Path(file).resolve().is_relative_to(r) for r in roots)

    def __enter__(self) -> StandIns:
        self._before = set(sys.modules)
        self._saved = {n: m for n, m in sys.modules.items() if self._own_name(n)}
        for name in self._saved:
            del sys.modules[name]
        sys.modules.update(self._modules())
        self._path = list(sys.path)
        sys.path.insert(0, str(self.base_dir))
        return self

    def __exit__(self, *exc: object) -> None:
        for name, module in list(sys.modules.items()):
            new = name not in self._before
            if self._own_name(name) or (new and self._from_user_folder(module)):
                if name.startswith("devices.") and self._from_user_folder(module):
                    self.user_modules[name] = module
                del sys.modules[name]
        sys.modules.update(self._saved)
        sys.path[:] = self._path
