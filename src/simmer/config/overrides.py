"""Overrides: the one route for changing a configuration's settings or devices.

An override is a dotted key and a value (``port_rx`` from the command line,
``drives.w0.error.x`` from a sweep's grid). :func:`apply_overrides` sets them in configuration
data before validation, and :func:`with_overrides` does the same to a loaded configuration by
validating its data again, so whatever changes a configuration is checked as a file is (two
equal ports are refused before any port opens).
"""

from __future__ import annotations

import copy
from collections.abc import Iterable, Mapping
from dataclasses import replace
from pathlib import Path
from typing import Any

from simmer.config.mazes import from_walls
from simmer.config.models import SimConfig
from simmer.config.validate import config_from_dict

__all__ = ["apply_overrides", "with_overrides"]


def apply_overrides(data: dict[str, Any], overrides: Iterable[tuple[str, Any]]) -> None:
    """Set each dotted key (``drives.w0.error.x``) in configuration data, making the tables
    on the way that are missing (a key the file left at its default). A ``*`` stands for each
    table at its level (``sensors.*.error``: every sensor's error). Raises ``KeyError`` if the
    way runs through something that is not a table, or a ``*`` finds no table."""
    for dotted, value in overrides:
        _set(data, dotted.split("."), value, dotted, ())


def _set(
    node: dict[str, Any], names: list[str], value: Any, dotted: str, way: tuple[str, ...]
) -> None:
    name, *rest = names
    if name == "*":
        tables = [key for key, child in node.items() if isinstance(child, dict)]
        if not rest or not tables:
            where = ".".join(way) or "the top level"
            raise KeyError(f"{dotted}: * stands for each table in {where}, and there is none")
        for key in tables:
            _set(node[key], rest, value, dotted, (*way, key))
        return
    if not rest:
        node[name] = copy.deepcopy(value)
        return
    child = node.get(name)
    if child is None:  # a table left unset (``maze``: None until a seed is given)
        child = node[name] = {}
    if not isinstance(child, dict):
        raise KeyError(f"{dotted}: {'.'.join((*way, name))} is a value, not a table")
    _set(child, rest, value, dotted, (*way, name))


def with_overrides(
    config: SimConfig, overrides: Mapping[str, Any], source: str | None = None
) -> SimConfig:
    """``config`` with ``overrides`` (dotted keys) applied to its data and validated again as
    a file's data is. Every problem is in a :class:`ConfigError` naming ``source`` (default:
    the configuration's). Its warnings stay those said when it was loaded."""
    maze_given = any(key == "maze" or key.startswith("maze.") for key in overrides)
    data = _config_data(config, maze_given)
    apply_overrides(data, overrides.items())
    source_path = Path(config.source)
    base_dir = source_path.parent if source_path.is_file() else Path.cwd()
    checked = config_from_dict(
        data, source or config.source, base_dir, original=bool(config.origin)
    )
    return replace(checked, source=config.source, warnings=config.warnings, origin=config.origin)


def _config_data(config: SimConfig, maze_given: bool = False) -> dict[str, Any]:
    """A validated configuration as data again: every setting, and each device's settings as
    given (a device's unset settings keep their defaults, as in its file); the settings its
    ``maze`` supplied (or, with ``maze_given``, the maze an override is about to name) are
    left to it."""
    data = config.settings.model_dump()
    if config.settings.maze is not None or maze_given:  # the maze supplies them (maze.seed)
        s = config.settings
        places = from_walls(s.walls, cell=s.wall_segment_length, start=s.zones.start).places()
        for key, value in places.items():
            default = type(s).model_fields[key].get_default(call_default_factory=True)
            if list(getattr(s, key)) in (value, list(default)):  # not the file's own place
                del data[key]
        for key in ("walls", "wall_segment_length", "floor_segment_length", "floor_seed"):
            del data[key]
        data["zones"].update(loading=None, dropoff=None, start=None)
    for spec in config.devices:
        params = spec.params.model_dump(exclude_unset=True)
        data.setdefault(spec.group, {})[spec.id] = {**params, "type": spec.kind}
    return data
