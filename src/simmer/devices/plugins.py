"""Plug-in files as importable modules, so what they define pickles into another process.

A configuration's plug-in file (``plugins = ["devices/tof.py"]``) is imported as the module
``simmer_plugin_<stem>_<code>``, where ``<code>`` spells the file's absolute path (in lower-case
base32). Its classes (a device kind, its ``Params``) pickle under that name, and another process
can import it again: importing :mod:`simmer.devices` puts :class:`PluginFinder` on
:data:`sys.meta_path`, which turns such a name back into the file and runs it. So a
configuration or a simulation using a plug-in unpickles in a fresh process (a worker of a
process pool) on the same machine, while the file is where it was: SimMeR's own classes come
first in such a pickle, so :mod:`simmer.devices` is imported before the plug-in module is
looked for (to unpickle a plug-in's object on its own, import :mod:`simmer.devices` first). A
name from Python's ``hash`` would not do: it is salted per process.

The name stays outside the ``simmer.`` namespace, which holds SimMeR's own modules only.
"""

from __future__ import annotations

import base64
import binascii
import importlib
import importlib.abc
import importlib.util
import os
import re
import sys
import types
from collections.abc import Sequence
from importlib.machinery import ModuleSpec
from pathlib import Path

PREFIX = "simmer_plugin_"
"""Start of every plug-in module's name; the finder answers only for these names."""


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


def import_plugin_file(path: Path) -> types.ModuleType:
    """Import the plug-in file at ``path`` (once per process) under its :func:`module_name`."""
    return importlib.import_module(module_name(path))


class PluginFinder(importlib.abc.MetaPathFinder):
    """Finds ``simmer_plugin_...`` modules: their names say which file to run."""

    def find_spec(
        self,
        fullname: str,
        path: Sequence[str] | None,
        target: types.ModuleType | None = None,
    ) -> ModuleSpec | None:
        """The spec for a plug-in module's file; None for any other name."""
        file = plugin_path(fullname)
        if file is None:
            return None
        if not file.is_file():
            raise ModuleNotFoundError(
                f"plug-in module {fullname} runs the file {file}, which no longer exists",
                name=fullname,
            )
        return importlib.util.spec_from_file_location(fullname, file)


def install_finder() -> None:
    """Put the :class:`PluginFinder` on :data:`sys.meta_path` (once)."""
    if not any(isinstance(finder, PluginFinder) for finder in sys.meta_path):
        sys.meta_path.append(PluginFinder())
