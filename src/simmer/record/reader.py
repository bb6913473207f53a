"""The one reader of a run folder's recordings: ``events.jsonl``, ``trace.csv`` and ``scans.csv``.

Plots, replays and their checks, ``simmer replay --check`` and the tests read these two files
only here (``tests/repository/test_run_folder_reader.py`` keeps it so), and their names are
defined only here (:data:`EVENTS`, :data:`TRACE`; the writers,
:class:`~simmer.record.eventlog.EventLog` and :class:`~simmer.record.trace.TraceWriter`, are
given the path). A run folder is data someone gave us, so every read is bounded: a file larger
than a recording holds (:data:`~simmer.options.MAX_RECORDING_BYTES`) is refused unread, and
each line of events is parsed by :func:`~simmer.untrusted.parse_json` (its size and nesting
checked first). Whatever goes wrong is one :class:`~simmer.errors.RunFolderError` (a
``ValueError``), one line naming the file; a plot or a replay says it as its own error.

Two readings of the events: :func:`read_events`, strict, gives back the very events a replay
feeds (a line that is not one is an error); :func:`event_objects`, lenient, gives each line
that is a JSON object (a plot draws what it knows and skips the rest). A last line cut off
before its newline (the disk filled, ``kill -9``) is left out of both, and of the trace.
"""

from __future__ import annotations

import csv
import io
import math
from collections.abc import Iterable, Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from simmer.errors import RunFolderError
from simmer.geometry import FloatArray
from simmer.options import MAX_RECORDING_BYTES
from simmer.record.eventlog import event_from_dict
from simmer.record.tracecheck import STEP, RowKey, TraceRows
from simmer.untrusted import parse_json
from simmer.world.events import Event, ResetEvent

EVENTS = "events.jsonl"
"""A run folder's event stream (:mod:`simmer.record.eventlog`)."""
TRACE = "trace.csv"
"""A run folder's trace (:mod:`simmer.record.trace`)."""


def _check_size(path: Path) -> None:
    """RunFolderError naming ``path`` if it is larger than a recording's files hold
    (:data:`MAX_RECORDING_BYTES`): it is refused rather than read whole. OSError if it
    cannot be looked at."""
    size = path.stat().st_size
    if size > MAX_RECORDING_BYTES:
        raise RunFolderError(
            f"{path} is {size:,} bytes, more than a recording holds ({MAX_RECORDING_BYTES:,})"
        )


# ----------------------------------------------------------------------------- events


def read_events(path: str | Path, max_steps: int | None = None) -> list[Event]:
    """Every event in an ``events.jsonl`` file, in order.

    A last line cut off before its newline is left out; any other line that is not an event
    is a :class:`RunFolderError` naming its line number, as is an event that would take a
    replay past ``max_steps`` steps (counted on across resets), a file larger than
    :data:`MAX_RECORDING_BYTES`, and one that cannot be read ("cannot read PATH: ...").
    """
    path = Path(path)
    try:
        _check_size(path)
        with path.open(encoding="utf-8", errors="strict") as file:
            return _events(path, file, max_steps)
    except (OSError, UnicodeError) as exc:
        raise RunFolderError(f"cannot read {path}: {exc}") from None


def _events(path: Path, lines: Iterable[str], max_steps: int | None) -> list[Event]:
    """The events of ``lines`` (see :func:`read_events`)."""
    events: list[Event] = []
    before = 0
    """Steps of the parts of the run before the last reset."""
    for number, line in enumerate(lines, 1):
        event = _event(path, number, line)
        if event is None:
            break
        if max_steps is not None and before + event.step > max_steps:
            after = f" ({before + event.step:,} counting on across resets)" if before else ""
            raise RunFolderError(
                f"{path} line {number}: step {event.step:,}{after} is beyond the replay "
                f"limit of {max_steps:,} steps (--max-seconds raises it)"
            )
        if isinstance(event, ResetEvent):
            before += event.step
        events.append(event)
    return events


def _event(path: Path, number: int, line: str) -> Event | None:
    """The event of line ``number``; None if it is a last line cut short, RunFolderError if
    it is not an event."""
    try:
        event = event_from_dict(_object(parse_json(line, "the line")))
        if event.step < 0:
            raise ValueError(f"step {event.step} is negative")
    except ValueError as exc:
        if not line.endswith("\n"):
            return None
        raise RunFolderError(f"{path} line {number}: {exc}") from None
    return event


def _object(value: Any) -> dict[str, Any]:
    if not isinstance(value, dict):
        raise ValueError(f"{type(value).__name__}, not a JSON object")
    return value


def event_objects(path: str | Path) -> Iterator[tuple[int, dict[str, Any]]]:
    """Each line of an ``events.jsonl`` file that is a JSON object, with its line number:
    lines that are not one (or not UTF-8) are skipped. :class:`RunFolderError` if the file is
    larger than :data:`MAX_RECORDING_BYTES` or cannot be read."""
    path = Path(path)
    try:
        _check_size(path)
        with path.open(encoding="utf-8", errors="replace") as file:
            for number, line in enumerate(file, 1):
                try:
                    value = parse_json(line, "an event")
                except ValueError:
                    continue
                if isinstance(value, dict):
                    yield number, value
    except OSError as exc:
        raise RunFolderError(f"cannot read {path}: {exc}") from None


# ----------------------------------------------------------------------------- the trace


@dataclass(frozen=True)
class TraceTable:
    """A ``trace.csv`` as text: its header and its rows, each a list of cells (whole lines
    only; a row may still have too few or too many cells)."""

    path: Path
    header: list[str]
    rows: list[list[str]]


def read_trace(path: str | Path) -> TraceTable:
    """The header and rows of a ``trace.csv``, its last line left out if it was cut before
    its newline; :class:`RunFolderError` ("cannot read PATH: ...") if the file cannot be read,
    is not UTF-8 or CSV, or is larger than :data:`MAX_RECORDING_BYTES`."""
    path = Path(path)
    try:
        _check_size(path)
        text = path.read_text(encoding="utf-8")
        if text and not text.endswith("\n"):
            text = text[: text.rfind("\n") + 1]
        reader = csv.reader(io.StringIO(text))
        header = next(reader, [])
        rows = list(reader)
    except (OSError, ValueError, csv.Error) as exc:  # a UnicodeError is a ValueError
        raise RunFolderError(f"cannot read {path}: {exc}") from None
    return TraceTable(path, header, rows)


def read_trace_rows(path: str | Path) -> TraceRows:
    """The whole rows of a ``trace.csv`` by where each was written (resets before it, step),
    to compare two traces (:func:`~simmer.record.tracecheck.first_difference`); a row with
    too few cells or no step is left out. RunFolderError as :func:`read_trace` says, and if
    the trace has no ``step`` column."""
    table = read_trace(path)
    header = table.header
    if STEP not in header:
        raise RunFolderError(f"cannot read {table.path}: {table.path} has no {STEP} column")
    step_at = header.index(STEP)
    rows: list[tuple[RowKey, list[str]]] = []
    part, previous = 0, -1
    for row in table.rows:
        if len(row) != len(header):
            continue
        try:
            step = int(row[step_at])
        except ValueError:
            continue
        if step < previous:  # a reset: the steps count from 0 again
            part += 1
        previous = step
        rows.append(((part, step), row))
    return TraceRows(header, rows)


# ----------------------------------------------------------------------------- the scans


SCANS = "scans.csv"
"""A run folder's LiDAR scans (:mod:`simmer.record.scans`)."""


@dataclass(frozen=True)
class RecordedScan:
    """One scan of ``scans.csv``: when it ended, its LiDAR and number, and per beam the
    distance (inches, 0: no return) and where it met something (world inches, NaN: none)."""

    time: float
    step: int
    device: str
    number: int
    distances: FloatArray
    x: FloatArray
    y: FloatArray

    @property
    def angles(self) -> FloatArray:
        """Each beam's angle, degrees clockwise from the LiDAR's front."""
        beams = len(self.distances)
        return np.arange(beams, dtype=np.float64) * np.float64(360.0 / beams)


def read_scans(path: str | Path) -> list[RecordedScan]:
    """Every whole scan of a ``scans.csv``, in order (its last line left out if cut before
    its newline). :class:`RunFolderError` naming the file (and line) if it cannot be read, is
    larger than :data:`~simmer.record.scans.MAX_SCAN_BYTES` allows, or a row is not a scan."""
    from simmer.record.scans import MAX_SCAN_BYTES, SCAN_COLUMNS

    path = Path(path)
    try:
        size = path.stat().st_size
        if size > MAX_SCAN_BYTES:
            raise RunFolderError(
                f"{path} is {size:,} bytes, more than a recording's scans hold "
                f"({MAX_SCAN_BYTES:,}, MAX_SCAN_BYTES)"
            )
        text = path.read_text(encoding="ascii")
    except (OSError, UnicodeError) as exc:
        raise RunFolderError(f"cannot read {path}: {exc}") from None
    lines = text.split("\n")[:-1]  # a last line without its newline is cut short: left out
    if not lines or lines[0] != ",".join(SCAN_COLUMNS):
        raise RunFolderError(
            f"{path} line 1: not a scans file's header (expected {','.join(SCAN_COLUMNS)})"
        )
    return [_scan(path, number, line) for number, line in enumerate(lines[1:], 2)]


def _scan(path: Path, number: int, line: str) -> RecordedScan:
    """The scan of line ``number``; RunFolderError naming the line if it is not one."""
    cells = line.split(",")
    try:
        if len(cells) != 7:
            raise ValueError(f"{len(cells)} cells, not 7")
        time, step, device, scan = float(cells[0]), int(cells[1]), cells[2], int(cells[3])
        beams = [np.array(cell.split(), dtype=np.float64) for cell in cells[4:]]
        if not beams[0].size or any(b.shape != beams[0].shape for b in beams):
            raise ValueError("its distances, x and y do not have one number per beam each")
        if not math.isfinite(time) or step < 0 or not device.isidentifier():
            raise ValueError("its time, step or device is not one")
    except ValueError as exc:
        raise RunFolderError(f"{path} line {number}: not a scan: {exc}") from None
    return RecordedScan(time, step, device, scan, *beams)
