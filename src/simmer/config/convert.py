"""Write a SimMeR ``config.py`` as the equivalent native TOML (``simmer convert``).

The TOML holds exactly the data :func:`~simmer.config.simmer_py.load_simmer_py` validates, so
loading it gives the same configuration. A comment written after a setting in the config.py
(``robot_width = 6  # Robot width in inches``) follows that setting; one after a device's entry
(``'u0': Ultrasonic(u0_info),  # front``) follows its table header.
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any

import tomlkit
from tomlkit.items import Array, InlineTable, Item

from simmer.config.loader import config_from_dict
from simmer.config.models import DEVICE_GROUPS
from simmer.config.simmer_py import SimmerPy, read_simmer_py
from simmer.errors import ConfigError, ConfigIssue

MULTILINE = frozenset({"walls"})


def convert_simmer_py(path: str | Path, output: str | Path | None = None) -> str:
    """The native TOML text for a SimMeR ``config.py``; written to ``output`` if given.

    The configuration is validated first, so a file that would not load is not converted.
    """
    source = read_simmer_py(path)
    config_from_dict(source.data, str(source.path), source.path.parent)
    out_dir = Path(output).resolve().parent if output is not None else source.path.parent
    text = tomlkit.dumps(_document(source, out_dir))
    if output is not None:
        Path(output).write_text(text, encoding="utf-8")
    return text


def _document(source: SimmerPy, out_dir: Path) -> tomlkit.TOMLDocument:
    doc = tomlkit.document()
    doc.add(tomlkit.comment(f"Converted from {source.path.name} by `simmer convert`."))
    doc.add(tomlkit.comment("Key names are SimMeR's; each device is a table named by its id."))
    doc.add(tomlkit.nl())
    settings = [k for k in source.data if k not in DEVICE_GROUPS]
    chosen = [k for k in settings if k not in source.spans]  # what the version detection chose
    if chosen:
        looks = source.origin.partition(": ")[0]
        doc.add(tomlkit.comment(f"{source.path.name} {looks};"))
        doc.add(tomlkit.comment("so these keep its replies and its reading of commands:"))
        for key in chosen:
            doc.add(key, _item(source, key, source.data[key]))
        doc.add(tomlkit.nl())
    in_file = [k for k in settings if k in source.spans]
    in_file.sort(key=lambda k: source.spans[k][0])
    for key in in_file:
        doc.add(key, _item(source, key, source.data[key]))
    for group in DEVICE_GROUPS:
        devices = source.data.get(group, {})
        if not devices:
            continue
        super_table = tomlkit.table(is_super_table=True)
        for device_id, values in devices.items():
            path = f"{group}.{device_id}"
            table = tomlkit.table()
            for key, value in values.items():
                written = (
                    _relative(source.path.parent / value, out_dir) if key == "module" else value
                )
                table.add(key, _item(source, f"{path}.{key}", written))
            entry_comment = source.comment_for(path)
            if entry_comment and not _same_line_as_a_key(source, path):
                table.comment(entry_comment)
            super_table.add(device_id, table)
        doc.add(tomlkit.nl())
        doc.add(group, super_table)
    return doc


def _same_line_as_a_key(source: SimmerPy, path: str) -> bool:
    """True if the entry's comment also belongs to one of its keys (a one-line info dict)."""
    first, last = source.spans[path]
    return any(
        key.startswith(f"{path}.") and first <= span[0] <= last
        for key, span in source.spans.items()
    )


def _relative(file: Path, out_dir: Path) -> str:
    return Path(os.path.relpath(file.resolve(), out_dir)).as_posix()


def _item(source: SimmerPy, key: str, value: Any) -> Item:
    try:
        item = _value(value)
    except ValueError as exc:
        raise ConfigError(source.path, [ConfigIssue(key, str(exc), source.line_of(key))]) from None
    if key in MULTILINE and isinstance(item, Array):
        item.multiline(True)
    comment = source.comment_for(key)
    if comment:
        item.comment(comment)
    return item


def _value(value: Any) -> Item:
    if value is None:
        raise ValueError("TOML has no None; delete this setting, or give it a value")
    if isinstance(value, dict):
        inline: InlineTable = tomlkit.inline_table()
        for key, inner in value.items():
            inline.append(key, _value(inner))
        return inline
    if isinstance(value, list):
        array: Array = tomlkit.array()
        array.extend(_value(v) for v in value)
        return array
    item: Item = tomlkit.item(value)
    return item
