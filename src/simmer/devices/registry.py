"""The registry of device kinds, by name (like Gymnasium's ``register``).

A configuration names a kind (``type = "ultrasonic"``); the registry finds the class. Users add
their own kinds with :func:`register_device_kind`, from a plug-in file named in the
configuration (``plugins = ["bumper.py"]``) or from an installed package's ``simmer.devices``
entry point; nothing in SimMeR needs editing.

A configuration's plug-ins register their kinds for that configuration alone: while a plug-in
loads, :func:`register_device_kind` puts its kinds in the plug-in's own table
(:mod:`simmer.devices.plugins`), and the configuration looks kinds up through a
:class:`DeviceKinds`: the process-wide kinds plus its plug-ins' kinds.

A kind may be registered as a ``"package.module:Class"`` string (an entry point's form), imported
on first use. The built-in kinds are registered so: the registry imports none of them itself,
so a module defining a kind (:mod:`simmer.compat.template`) may import :mod:`simmer.devices`
without an import cycle, and only what a configuration uses is imported.
"""

from __future__ import annotations

import importlib
import inspect
from collections.abc import Callable
from dataclasses import dataclass
from importlib.metadata import entry_points
from typing import TypeVar, cast, overload

import numpy as np

from simmer.devices.base import Device, DeviceParams
from simmer.devices.plugins import COLLECTING, Kinds, plugin_kinds
from simmer.errors import DeviceKindError

BUILTIN_KINDS = {
    "motor": "simmer.devices.motor:Motor",
    "drive": "simmer.devices.drive:Drive",
    "ultrasonic": "simmer.devices.sensors:Ultrasonic",
    "gyroscope": "simmer.devices.sensors:Gyroscope",
    "compass": "simmer.devices.sensors:Compass",
    "infrared": "simmer.devices.sensors:Infrared",
    "gripper": "simmer.devices.gripper:Gripper",
    "lidar": "simmer.devices.lidar:Lidar",
    "tof": "simmer.devices.tof:TimeOfFlight",
    "imu": "simmer.devices.motion:Imu",
    "encoder": "simmer.devices.motion:Encoder",
    # a device class written for the original SimMeR
    "simmer_device": "simmer.compat.template:SimmerDevice",
}
"""SimMeR's own kinds: name -> ``"module:Class"``."""

_KINDS: Kinds = dict(BUILTIN_KINDS)
"""Every registered kind: its class, or its ``"module:Class"`` string until first used."""
_ENTRY_POINTS_LOADED = False
ENTRY_POINT_GROUP = "simmer.devices"

D = TypeVar("D", bound=type[Device])


@overload
def register_device_kind(
    name: str, cls: None = None, *, replace: bool = False
) -> Callable[[D], D]: ...


@overload
def register_device_kind(name: str, cls: D, *, replace: bool = False) -> D: ...


@overload
def register_device_kind(name: str, cls: str, *, replace: bool = False) -> str: ...


def register_device_kind(
    name: str, cls: type[Device] | str | None = None, *, replace: bool = False
) -> Callable[[D], D] | type[Device] | str:
    """Register ``cls`` as device kind ``name``; usable as a call or a class decorator.

    ``cls`` may be a ``"package.module:Class"`` string, imported when the kind is first used.
    A second registration under one name is an error unless it is the same class (a module
    imported twice) or ``replace=True``. Called while a configuration's plug-in loads, it
    registers the kind for that configuration only.
    """
    table = COLLECTING.get()
    kinds = _KINDS if table is None else table

    def _register(kind_cls: D) -> D:
        check_device_kind(kind_cls)
        _claim(kinds, name, kind_cls, replace)
        kind_cls.kind = name
        kinds[name] = kind_cls
        return kind_cls

    if cls is None:
        return _register
    if isinstance(cls, str):
        _claim(kinds, name, cls, replace)
        kinds[name] = cls
        return cls
    return _register(cls)


def _claim(kinds: Kinds, name: str, new: type[Device] | str, replace: bool) -> None:
    """Refuse ``new`` under ``name`` if another class holds the name (unless ``replace``), in
    ``kinds`` or, for a plug-in's kind, process-wide."""
    existing = kinds.get(name, _KINDS.get(name))
    if existing is not None and not replace and _target(existing) != _target(new):
        raise DeviceKindError(
            f"device kind {name!r} is already registered by {_target(existing)}; "
            f"choose another name for {_target(new)}"
        )


def _target(cls: type[Device] | str) -> str:
    """Where a kind's class lives, as ``"module:Class"``."""
    return cls if isinstance(cls, str) else f"{cls.__module__}:{cls.__qualname__}"


def _resolve(name: str, kinds: Kinds | None = None) -> type[Device] | None:
    """The class registered as ``name`` in ``kinds`` (default: process-wide), imported and
    checked now if registered as a string."""
    kinds = _KINDS if kinds is None else kinds
    entry = kinds.get(name)
    if not isinstance(entry, str):
        return entry
    module_name, _, qualname = entry.partition(":")
    try:
        found: object = importlib.import_module(module_name)
        for part in qualname.split("."):
            found = getattr(found, part)
    except (ImportError, AttributeError) as exc:
        raise DeviceKindError(f"device kind {name!r}: cannot import {entry}: {exc}") from exc
    check_device_kind(found)  # raises unless it is a Device subclass
    kind_cls = cast(type[Device], found)
    kind_cls.kind = name
    kinds[name] = kind_cls
    return kind_cls


def check_device_kind(cls: object) -> None:
    """Raise :class:`DeviceKindError` unless ``cls`` honours the device interface."""
    problems: list[str] = []
    if not (inspect.isclass(cls) and issubclass(cls, Device)):
        raise DeviceKindError(f"{cls!r} is not a subclass of simmer.devices.Device")
    if cls.category not in ("motor", "drive", "sensor"):
        problems.append(f"category must be 'motor', 'drive' or 'sensor', not {cls.category!r}")
    if not (inspect.isclass(cls.Params) and issubclass(cls.Params, DeviceParams)):
        problems.append("Params must be a subclass of simmer.devices.DeviceParams")
    if cls.simulate is Device.simulate:
        problems.append("it must override simulate(self, value, world) -> float")
    else:
        params = list(inspect.signature(cls.simulate).parameters)
        if len(params) != 3:
            problems.append(f"simulate must take (self, value, world), not ({', '.join(params)})")
    outline = np.asarray(cls.default_outline)
    if outline.ndim != 2 or outline.shape[1] != 2 or outline.shape[0] < 3:
        problems.append("default_outline must be an array of at least 3 (x, y) points")
    if problems:
        raise DeviceKindError(f"device kind {_target(cls)} is not usable: " + "; ".join(problems))


def device_kinds() -> dict[str, type[Device]]:
    """Every registered kind by name (built-ins, plug-ins, installed entry points)."""
    _load_entry_points()
    found = {name: _resolve(name) for name in list(_KINDS)}
    return {name: cls for name, cls in found.items() if cls is not None}


def get_device_kind(name: str) -> type[Device] | None:
    """The kind registered as ``name``, or None."""
    _load_entry_points()
    return _resolve(name)


def _load_entry_points() -> None:
    """Register installed packages' kinds (once per process), as strings imported on use."""
    global _ENTRY_POINTS_LOADED  # noqa: PLW0603 - load installed plug-ins once per process
    if _ENTRY_POINTS_LOADED:
        return
    _ENTRY_POINTS_LOADED = True
    for ep in entry_points(group=ENTRY_POINT_GROUP):
        register_device_kind(ep.name, f"{ep.module}:{ep.attr}")


@dataclass(frozen=True)
class DeviceKinds:
    """The kinds one configuration can use: the process-wide kinds and its plug-ins' own.

    ``plugins`` are the configuration's plug-ins as loaded (a file's absolute path or an
    installed module's name); each is loaded once per process, on first use, so a pickled
    configuration finds its kinds in another process too.
    """

    plugins: tuple[str, ...] = ()

    def _own(self) -> Kinds:
        own: Kinds = {}
        for entry in self.plugins:
            own |= plugin_kinds(entry)
        return own

    def get(self, name: str) -> type[Device] | None:
        """The kind called ``name``, or None."""
        own = self._own()
        return _resolve(name, own) if name in own else get_device_kind(name)

    def all(self) -> dict[str, type[Device]]:
        """Every kind by name."""
        own = self._own()
        found = device_kinds() | {name: _resolve(name, own) for name in list(own)}
        return {name: cls for name, cls in found.items() if cls is not None}
