"""Write a SimMeR ``config.py`` as the equivalent native TOML (``simmer convert``).

The TOML holds exactly the data :func:`~simmer.config.simmer_py.load_simmer_py` validates, so
loading it gives the same configuration. A comment written after a setting in the config.py
(``robot_width = 6  # Robot width in inches``) follows that setting; one after a device's entry
(``'u0': Ultrasonic(u0_info),  # front``) follows its table header. A setting commented out
(``# 'error': 0.02,`` in an info dictionary, ``# simulate_list = ['u0']``) stays commented out,
written in TOML where it was (``# error = 0.02`` in the device's table), so the lab's toggles
are still one uncomment away. What a comment says that is no longer true (the original's
"placeholder, not implemented" beside ``rand_bias``) is left out.
"""

from __future__ import annotations

import os
import re
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import tomlkit
from tomlkit.items import Array, Comment, InlineTable, Item, Table

from simmer.config.loader import config_from_dict
from simmer.config.models import DEVICE_GROUPS
from simmer.config.simmer_py import CommentedOut, SimmerPy, read_simmer_py
from simmer.errors import ConfigError, ConfigIssue

MULTILINE = frozenset({"walls"})
STALE = re.compile(r"\s*\(?placeholder, not implemented\)?", re.IGNORECASE)
"""What the originals' comments say that SimMeR 2 made untrue (it draws drive biases)."""


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
    top_commented = [c for c in source.commented_out if not c.table]
    for entry in _interleave(in_file, source.spans, top_commented):
        if isinstance(entry, CommentedOut):
            doc.add(_commented(entry, set_too=entry.key in source.data))
        else:
            doc.add(entry, _item(source, entry, source.data[entry]))
    for group in DEVICE_GROUPS:
        devices = source.data.get(group, {})
        if not devices:
            continue
        super_table = tomlkit.table(is_super_table=True)
        for device_id, values in devices.items():
            path = f"{group}.{device_id}"
            super_table.add(device_id, _device_table(source, path, values, out_dir))
        doc.add(tomlkit.nl())
        doc.add(group, super_table)
    return doc


def _device_table(source: SimmerPy, path: str, values: dict[str, Any], out_dir: Path) -> Table:
    """One device's table, its commented-out settings where they were written."""
    table = tomlkit.table()
    commented = [c for c in source.commented_out if c.table == path]
    spans = {
        key: source.spans[f"{path}.{key}"] for key in values if f"{path}.{key}" in source.spans
    }
    for entry in _interleave(list(values), spans, commented):
        if isinstance(entry, CommentedOut):
            table.add(_commented(entry, set_too=entry.key in values))
            continue
        value = values[entry]
        written = _relative(source.path.parent / value, out_dir) if entry == "module" else value
        table.add(entry, _item(source, f"{path}.{entry}", written))
    entry_comment = _current(source.comment_for(path))
    if entry_comment and not _same_line_as_a_key(source, path):
        table.comment(entry_comment)
    return table


def _interleave(
    keys: list[str], spans: dict[str, tuple[int, int]], commented: list[CommentedOut]
) -> Iterator[str | CommentedOut]:
    """``keys`` in their order, each commented-out setting just before the first key written
    after it in the config.py (the rest at the end)."""
    pending = sorted(commented, key=lambda c: c.line)
    for key in keys:
        line = spans[key][0] if key in spans else None
        while pending and line is not None and pending[0].line < line:
            yield pending.pop(0)
        yield key
    yield from pending


def _commented(setting: CommentedOut, *, set_too: bool) -> Comment:
    """A commented-out setting as a TOML comment: ``# error = 0.02``."""
    key = tomlkit.key(setting.key).as_string()
    try:
        text = f"{key} = {_value(setting.value).as_string()}"
    except ValueError:  # None: no TOML for it; keep what the config.py said
        text = f"{key} = {setting.value!r}"
    notes = [note for note in (_current(setting.comment),) if note]
    if set_too:
        notes.append(f"uncomment only after deleting the other `{setting.key}` line")
    return tomlkit.comment(f"{text}  # {'; '.join(notes)}" if notes else text)


def _current(comment: str | None) -> str | None:
    """``comment`` without what is no longer true (:data:`STALE`); None if nothing is left."""
    if comment is None:
        return None
    return STALE.sub("", comment).strip() or None


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
    comment = _current(source.comment_for(key))
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
