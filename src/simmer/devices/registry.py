"""The registry of device kinds, by name (like Gymnasium's ``register``).

A configuration names a kind (``type = "ultrasonic"``); the registry finds the class. Users add
their own kinds with :func:`register_device_kind`, from a plug-in file named in the
configuration (``plugins = ["bumper.py"]``) or from an installed package's ``simmer.devices``
entry point; nothing in SimMeR needs editing.
"""

from __future__ import annotations

import inspect
from collections.abc import Callable
from importlib.metadata import entry_points
from typing import TypeVar

import numpy as np

from simmer.devices.base import Device, DeviceParams
from simmer.errors import DeviceKindError

_KINDS: dict[str, type[Device]] = {}
_ENTRY_POINTS_LOADED = False
ENTRY_POINT_GROUP = "simmer.devices"

D = TypeVar("D", bound=type[Device])


def register_device_kind(
    name: str, cls: type[Device] | None = None, *, replace: bool = False
) -> Callable[[D], D] | type[Device]:
    """Register ``cls`` as device kind ``name``; usable as a call or a class decorator.

    A second registration under one name is an error unless it is the same class (a module
    imported twice) or ``replace=True``.
    """

    def _register(kind_cls: D) -> D:
        check_device_kind(kind_cls)
        existing = _KINDS.get(name)
        if existing is not None and not replace and _qualname(existing) != _qualname(kind_cls):
            raise DeviceKindError(
                f"device kind {name!r} is already registered by {_qualname(existing)}; "
                f"choose another name for {_qualname(kind_cls)}"
            )
        kind_cls.kind = name
        _KINDS[name] = kind_cls
        return kind_cls

    if cls is None:
        return _register
    return _register(cls)


def _qualname(cls: type) -> str:
    return f"{cls.__module__}.{cls.__qualname__}"


def check_device_kind(cls: type) -> None:
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
        raise DeviceKindError(f"device kind {_qualname(cls)} is not usable: " + "; ".join(problems))


def device_kinds() -> dict[str, type[Device]]:
    """Every registered kind by name (built-ins, plug-ins, installed entry points)."""
    _load_entry_points()
    return dict(_KINDS)


def get_device_kind(name: str) -> type[Device] | None:
    """The kind registered as ``name``, or None."""
    _load_entry_points()
    return _KINDS.get(name)


def _load_entry_points() -> None:
    global _ENTRY_POINTS_LOADED  # noqa: PLW0603 - load installed plug-ins once per process
    if _ENTRY_POINTS_LOADED:
        return
    _ENTRY_POINTS_LOADED = True
    for ep in entry_points(group=ENTRY_POINT_GROUP):
        cls = ep.load()
        register_device_kind(ep.name, cls)
