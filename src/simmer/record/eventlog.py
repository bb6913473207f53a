"""``events.jsonl``: a run's event stream as JSON lines, written as it happens and read back.

One JSON object per line, ``{"type":"command","time":1.5,"message":"u0","replies":[12.3],...}``:
the event's fields under their own names, and ``type`` naming its class (:data:`TYPE_NAMES`).
A pose is ``[x, y, heading]``, held keys a sorted list. JSON has no NaN or infinity, and
replies carry both (+inf: a drive accepted; NaN: a bad command, a busy drive), so a float
that is not finite is the string ``"nan"``, ``"inf"`` or ``"-inf"``; every other float is
written in the shortest form that reads back to the same bits. :func:`event_from_dict` gives
back the very event of a parsed line (what replay needs; :func:`simmer.record.reader.read_events`
reads the file with it); any JSON reader reads the file.

:class:`EventLog` writes each line with one unbuffered ``write``, so after Ctrl-C, a crash or
``kill -9`` the file holds every event up to the last, each line whole. It leaves out
:class:`~simmer.world.events.StepEvent`: one per step (60 a second), each only a pose, which
the trace keeps at a fixed rate (:mod:`simmer.record.trace`) and a replay recomputes. The
run's last step is written at :meth:`EventLog.close` (unless an event came after it), so a
replay knows where the run stopped.
"""

from __future__ import annotations

import errno
import json
import math
import os
from collections.abc import Callable
from contextlib import suppress
from dataclasses import fields
from functools import lru_cache
from pathlib import Path
from typing import Any, get_type_hints

from simmer.geometry import Pose
from simmer.options import MAX_RECORDING_BYTES
from simmer.world.events import (
    BeliefEvent,
    BlockedMoveEvent,
    CollisionEndEvent,
    CollisionEvent,
    CommandEvent,
    EstimateEvent,
    Event,
    KeysEvent,
    PlaceEvent,
    ReachedEvent,
    ResetEvent,
    RunEvent,
    StepEvent,
)

TYPE_NAMES: dict[type[Event], str] = {
    CommandEvent: "command",
    StepEvent: "step",
    CollisionEvent: "collision",
    CollisionEndEvent: "collision-end",
    BlockedMoveEvent: "blocked-move",
    ResetEvent: "reset",
    KeysEvent: "keys",
    PlaceEvent: "place",
    ReachedEvent: "reached",
    RunEvent: "run",
    BeliefEvent: "belief",
    EstimateEvent: "estimate",
}
"""The ``type`` written for each event class."""
EVENT_TYPES = {name: cls for cls, name in TYPE_NAMES.items()}
NOT_FINITE = {"nan": math.nan, "inf": math.inf, "-inf": -math.inf}
"""How a float that JSON cannot hold is written, and what it reads back as."""


class RecordingBudget:
    """Bytes a recording's files may still take (:data:`MAX_RECORDING_BYTES` unless told), shared
    by its writers; :meth:`take` says whether a write fits. ``covers`` says which files it
    bounds and how to raise it, for :meth:`why`."""

    def __init__(
        self,
        limit: int = MAX_RECORDING_BYTES,
        covers: str = "events.jsonl and trace.csv together; --record-limit MB raises it",
    ) -> None:
        self.limit = limit
        self.covers = covers
        self.used = 0

    def take(self, size: int) -> bool:
        """Count ``size`` more bytes if they fit (True), else nothing (False)."""
        if self.used + size > self.limit:
            return False
        self.used += size
        return True

    def why(self) -> str:
        """Why the recording stopped, naming the limit and how to raise it."""
        return f"it reached the size limit of {self.limit / 2**20:,.0f} MB ({self.covers})"


def stop_reason(exc: OSError) -> str:
    """Why a write failed, in words for "the recording in DIR stopped: ..."."""
    if exc.errno in (errno.ENOSPC, errno.EDQUOT):
        return "disk full"
    return exc.strerror or str(exc)


def write_all(write: Callable[[bytes], int | None], data: bytes) -> None:
    """Write all of ``data`` with ``write`` (an unbuffered file's, which may write part of
    it), in one system call unless the system writes less; OSError as the file raises it."""
    done = write(data) or 0
    while done < len(data):
        done += write(data[done:]) or 0


# ----------------------------------------------------------------------------- writing


class BoundedFile:
    """A run folder's file written in whole records (lines, rows), each in one system call,
    within ``budget``: a write that does not fit, or fails (a full disk), stops the file. It is
    cut back to its last whole record (which needs no space on a full disk), :attr:`stopped`
    says why and ``on_stop`` is told; the run and its other files go on."""

    def __init__(
        self, path: str | Path, budget: RecordingBudget, on_stop: Callable[[str], None] | None
    ) -> None:
        self.path = Path(path)
        self._file = self.path.open("wb", buffering=0)
        self._send = self._file.write
        self._budget = budget
        self._on_stop = on_stop
        self._size = 0
        """Bytes of whole records in the file."""
        self._closed = False
        self.stopped: str | None = None
        """Why the file stopped before the run ended (None: it did not)."""

    def _put(self, data: bytes) -> bool:
        """Write whole records if they fit the budget and the disk (True); else stop."""
        if self.stopped is not None:
            return False
        if not self._budget.take(len(data)):
            self.stop(self._budget.why())
            return False
        try:
            write_all(self._send, data)
        except OSError as exc:
            self.stop(stop_reason(exc))
            return False
        self._size += len(data)
        return True

    def stop(self, reason: str) -> None:
        """Write nothing more, cutting the file back to its last whole record, and say why
        (again: nothing)."""
        if self.stopped is not None:
            return
        self.stopped = reason
        with suppress(OSError, ValueError):  # ValueError: closed already
            os.ftruncate(self._file.fileno(), self._size)
        if self._on_stop is not None:
            self._on_stop(reason)

    def _close_file(self) -> None:
        self._closed = True
        with suppress(OSError):
            self._file.close()


def _number(value: float) -> str:
    """A float as JSON text: exact, or ``"nan"``, ``"inf"``, ``"-inf"`` (see the module doc)."""
    text = repr(value)
    return f'"{text}"' if "n" in text else text  # only nan, inf and -inf have an n


def _numbers(values: tuple[float, ...]) -> str:
    """A pose or replies as a JSON list of numbers (all at once unless one is not finite:
    a Python call per number would cost twice as much)."""
    text = ",".join(map(repr, values))
    if "n" in text:
        text = ",".join(map(_number, values))
    return "[" + text + "]"


_string = lru_cache(maxsize=1024)(json.dumps)
"""A string as JSON text; a program sends the same few messages again and again."""


def _names(values: frozenset[str]) -> str:
    return "[" + ",".join(map(_string, sorted(values))) + "]"


_WRITERS: dict[Any, Callable[[Any], str]] = {
    float: _number,
    int: str,
    str: _string,
    Pose: _numbers,
    tuple[float, ...]: _numbers,
    frozenset[str]: _names,
}
"""How each type of event field is written (:data:`_READERS` reads it back)."""


def _layout(cls: type[Event]) -> tuple[str, tuple[tuple[str, str, Callable[[Any], str]], ...]]:
    """How a line of this event class starts, then each field's name, key and writer."""
    hints = get_type_hints(cls)
    keys = tuple((f.name, f',"{f.name}":', _WRITERS[hints[f.name]]) for f in fields(cls))
    return f'{{"type":"{TYPE_NAMES[cls]}"', keys


_LAYOUTS = {cls: _layout(cls) for cls in TYPE_NAMES}


_COMMAND_LINE = '{"type":"command","time":%s,"message":%s,"replies":%s,"step":%d,"client":%s}\n'
"""A command's line: what :data:`_LAYOUTS` gives for :class:`CommandEvent`, spelt out, since
nearly every event a program causes is one (a test checks the two agree)."""


def event_line(event: Event) -> str:
    """An event as one line of JSON, with its newline: ``type`` first, then its fields.

    Put together here rather than by :func:`json.dumps`, which would need a dictionary made
    first and costs half as much again; a recorder writes one for every command.
    """
    if type(event) is CommandEvent:
        return _COMMAND_LINE % (
            _number(event.time),
            _string(event.message),
            _numbers(event.replies),
            event.step,
            _string(event.client),
        )
    start, layout = _LAYOUTS[type(event)]
    parts = [start]
    for name, key, write in layout:
        parts.append(key)
        parts.append(write(getattr(event, name)))
    parts.append("}\n")
    return "".join(parts)


# ----------------------------------------------------------------------------- reading


def _float(value: Any) -> float:
    """A float as :func:`_number` wrote it."""
    if isinstance(value, str):
        return NOT_FINITE[value]
    if isinstance(value, int | float) and not isinstance(value, bool):
        return float(value)
    raise ValueError(f"not a number: {value!r}")


_READER_OF: dict[Any, Callable[[Any], Any]] = {
    float: _float,
    int: int,
    str: str,
    Pose: lambda value: Pose(*(_float(v) for v in value)),
    tuple[float, ...]: lambda value: tuple(_float(v) for v in value),
    frozenset[str]: lambda value: frozenset(str(v) for v in value),
}
_READERS = {
    cls: {name: _READER_OF[hint] for name, hint in get_type_hints(cls).items()}
    for cls in TYPE_NAMES
}


def event_from_dict(data: dict[str, Any]) -> Event:
    """The event of one parsed line (ValueError if ``data`` is not one)."""
    kind = data.get("type", "")
    cls = EVENT_TYPES.get(kind) if isinstance(kind, str) else None
    if cls is None:
        raise ValueError(f"unknown event type {data.get('type')!r}")
    readers = _READERS[cls]
    try:
        values = {name: readers[name](value) for name, value in data.items() if name != "type"}
        return cls(**values)
    except (KeyError, TypeError, ValueError, OverflowError) as exc:  # a step of Infinity
        raise ValueError(f"not a {data['type']} event: {exc}") from None


# ----------------------------------------------------------------------------- the observer


class EventLog(BoundedFile):
    """An observer writing every event but the steps to ``events.jsonl`` (see the module doc).

    The file takes its bytes from ``budget``. A write that does not fit, or fails (a full
    disk), stops the log (as :meth:`stop` does): the file is cut back to its last whole line,
    :attr:`stopped` says why and ``on_stop`` is called with it; the run goes on unrecorded."""

    def __init__(
        self,
        path: str | Path,
        budget: RecordingBudget | None = None,
        on_stop: Callable[[str], None] | None = None,
    ) -> None:
        super().__init__(path, budget or RecordingBudget(), on_stop)
        self._last_step: StepEvent | None = None
        self.written = 0
        """Events written so far."""

    def __call__(self, event: Event) -> None:
        """Observe one event: write it, or keep a step for :meth:`close`."""
        if type(event) is StepEvent:
            self._last_step = event
            return
        if self._closed or self.stopped:  # a simulation thread that outlived the run
            return
        self._last_step = None
        self._write(event_line(event).encode("utf-8"))

    def _write(self, line: bytes) -> None:
        if self._put(line):
            self.written += 1

    def close(self) -> None:
        """Write the run's last step if nothing came after it, and close the file (again:
        nothing)."""
        if self._closed:
            return
        if self._last_step is not None and self.stopped is None:
            self._write(event_line(self._last_step).encode("utf-8"))
        self._close_file()
