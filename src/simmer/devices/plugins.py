"""Plug-ins loaded for one configuration, without touching the process's import machinery.

A configuration's plug-in (``plugins = ["devices/bumper.py"]``, or an installed module's name) is
loaded once per process: a file runs as the module ``simmer_plugin_<stem>_<code>``, where
``<code>`` spells the file's absolute path (in lower-case base32), so its name is the same in
every process (a name from Python's ``hash`` would not do: it is salted per process). The kinds
it registers while it runs (:func:`simmer.devices.register_device_kind`) are collected for the
configuration naming it, not put in the process-wide registry, so two configurations may each
have their own kind called ``"bumper"``.

The module is in :data:`sys.modules` only while its file runs (what it defines may look itself
up there), and no finder is installed. An instance of a plug-in's device or settings class
pickles naming the module (:func:`by_plugin_file`), and another process on the same machine
turns that name back into the file and loads it there, while the file is where it was. A
plug-in's other classes (an enum among its settings) do not pickle.

The name stays outside the ``simmer.`` namespace, which holds SimMeR's own modules only.
"""

from __future__ import annotations

import base64
import binascii
import importlib
import importlib.util
import os
import re
import sys
import types
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from contextvars import ContextVar
from pathlib import Path
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from simmer.devices.base import Device

PREFIX = "simmer_plugin_"
"""Start of every plug-in module's name."""

Kinds = dict[str, "type[Device] | str"]
"""Device kinds by name: a class, or its ``"module:Class"`` string until first used."""

COLLECTING: ContextVar[Kinds | None] = ContextVar("simmer_plugin_kinds", default=None)
"""Where :func:`~simmer.devices.register_device_kind` puts a kind while a plug-in loads."""

_LOADED: dict[str, Kinds] = {}
"""Each loaded plug-in (a file's absolute path or a module's name) and the kinds it registered."""
_MODULES: dict[str, types.ModuleType] = {}
"""Each loaded plug-in file's module, by its :func:`module_name`."""


def module_name(path: Path) -> str:
    """The plug-in file's module name: the same in every process (from its resolved path)."""
    path = path.resolve()
    code = base64.b32encode(os.fsencode(path)).decode("ascii").rstrip("=").lower()
    stem = re.sub(r"\W", "_", path.stem, flags=re.ASCII)
    return f"{PREFIX}{stem}_{code}"


def plugin_path(name: str) -> Path | None:
    """The file a plug-in module name spells, or None if ``name`` is not one."""
    if not name.startswith(PREFIX) or "." in name[len(PREFIX) :]:
        return None
    code = name.rpartition("_")[2].upper()
    try:
        raw = base64.b32decode(code + "=" * (-len(code) % 8))
    except (binascii.Error, ValueError):
        return None
    path = Path(os.fsdecode(raw))
    return path if path.is_absolute() else None  # module_name spells only absolute paths


def plugin_kinds(entry: str) -> Kinds:
    """Load a plug-in once per process: ``entry`` is a ``.py`` file's absolute path or an
    installed module's name. Returns the kinds it registered while it loaded (a module imported
    before, outside a configuration, registered its kinds process-wide instead)."""
    if entry not in _LOADED:
        kinds: Kinds = {}
        with collecting(kinds):
            if Path(entry).is_absolute():
                _run_file(Path(entry))
            else:
                importlib.import_module(entry)
        _LOADED[entry] = kinds
    return _LOADED[entry]


@contextmanager
def collecting(kinds: Kinds) -> Iterator[None]:
    """Kinds registered in this block go into ``kinds`` instead of the process-wide registry."""
    token = COLLECTING.set(kinds)
    try:
        yield
    finally:
        COLLECTING.reset(token)


def _run_file(path: Path) -> types.ModuleType:
    """Run a plug-in file as its module, which is in :data:`sys.modules` only meanwhile."""
    name = module_name(path)
    if not path.is_file():
        raise ModuleNotFoundError(
            f"plug-in module {name} runs the file {path}, which no longer exists", name=name
        )
    spec = importlib.util.spec_from_file_location(name, path)
    assert spec is not None
    assert spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    sys.modules[name] = module
    try:
        spec.loader.exec_module(module)
    finally:
        del sys.modules[name]
    _MODULES[name] = module
    return module


def plugin_class(name: str, qualname: str) -> type:
    """The class ``qualname`` of plug-in module ``name``, loading its file if not loaded yet."""
    path = plugin_path(name)
    if path is None:
        raise ModuleNotFoundError(f"{name} is not a plug-in module name", name=name)
    plugin_kinds(str(path))
    found: Any = _MODULES[name]
    for part in qualname.split("."):
        found = getattr(found, part)
    assert isinstance(found, type)
    return found


def by_plugin_file(cls: type, reduced: str | tuple[Any, ...]) -> str | tuple[Any, ...]:
    """``reduced`` (what ``__reduce_ex__`` made of an instance of ``cls``), naming ``cls`` by
    its plug-in module and name when ``cls`` comes from a plug-in file, so the other process
    loads the file instead of importing a module it has no finder for."""
    if isinstance(reduced, str) or not cls.__module__.startswith(PREFIX):
        return reduced
    make, args, *rest = reduced
    if not args or args[0] is not cls:
        return reduced
    return (_rebuild, (cls.__module__, cls.__qualname__, make, args[1:]), *rest)


def _rebuild(name: str, qualname: str, make: Callable[..., Any], args: tuple[Any, ...]) -> Any:
    """Unpickle an instance of a plug-in's class: ``make(cls, *args)`` as pickle would."""
    return make(plugin_class(name, qualname), *args)
