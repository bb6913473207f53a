"""``trace.csv``: the true pose and every sensor's last reading, 30 rows per simulated second.

Columns: ``time`` (simulated seconds), ``step``, ``x`` and ``y`` (inches), ``heading``
(degrees from +y, clockwise), ``collisions`` (so far), then one column per sensor, named by
its id, holding the last value that sensor answered a command with (blank until its first
reading; ``nan`` for a NaN reply). Plain numbers, a header row, commas: Excel, pandas
(``pd.read_csv``) and the ``csv`` module read it as it is. Numbers have 10 significant digits
(:data:`NUMBER`): a millionth of an inch or a degree, and of a second for runs under two
hours; exact digits (17 for a noisy reading) would make the file half as large again and the
rows three times as dear to write. ``events.jsonl`` has every reply exactly.

Why 30 rows a second (:data:`TRACE_RATE`): a row every step (60 a second) doubles the file and
the cost for nothing a plot or a lab report can see; the robot moves at most 0.2 in between
two rows at the lab's speeds. A row is written at the first step of every 1/30 s of simulated
time (every second step at 60 steps a second; every step below 30), plus the start and the
last step. The time restarts at 0 after a reset (the robot is back at its start).

Rows are written once a simulated second (:data:`HELD_SECONDS`) or a wall-clock second,
whichever comes first (a write per row would cost more than making it), so after ``kill -9``
at most its last simulated second is missing (rows were written every 1,024 rows: a fast run
killed had 33 s of events and no rows); ``events.jsonl`` has every event, and a replay
(:func:`simmer.record.retrace`) writes the trace again. The file takes its bytes from the
recording's budget (:class:`~simmer.record.eventlog.RecordingBudget`); a write that does not
fit, or fails (a full disk), stops the trace at its last whole row, and
:attr:`TraceWriter.rows` counts only rows in the file.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Sequence
from pathlib import Path

from simmer.geometry import Pose
from simmer.protocol import command_ids, parse_command
from simmer.record.eventlog import BoundedFile, RecordingBudget
from simmer.world.events import CollisionEvent, CommandEvent, Event, ResetEvent, StepEvent

TRACE_RATE = 30.0
"""Rows per simulated second (at most one per step)."""
POSE_COLUMNS = ("time", "step", "x", "y", "heading", "collisions")
"""The columns before the sensors'."""
FLUSH_INTERVAL = 1.0
"""Wall-clock seconds between flushes of the file."""
NUMBER = "%.10g"
"""How a number is written (``nan`` and ``inf`` as themselves)."""
ROW = f"{NUMBER},%d,{NUMBER},{NUMBER},{NUMBER},%d"
"""A row up to its sensors' columns."""
HELD_SECONDS = 1.0
"""Simulated seconds of rows held before they are written, at most: what ``kill -9`` loses."""
MAX_MESSAGES = 1024
"""Distinct messages whose sensor columns are remembered (a program repeats a few)."""


def _reading_columns(message: str, ids: list[str], columns: dict[str, int]) -> list[str]:
    """The column each command of ``message`` fills: its id, or for a sensor with several
    readings (``i0-1`` is a column: an IMU's axis) its id and the command's value."""
    if not any(f"{i}-1" in columns for i in ids):
        return ids
    named = []
    for device, text in zip(ids, message.strip().split(","), strict=True):
        value = parse_command(text).value if f"{device}-1" in columns else 0.0
        named.append(device if value == 0.0 else f"{device}-{value:g}")  # i0-7: no column
    return named


def trace_columns(sensors: Sequence[str]) -> list[str]:
    """The header row of a trace with these sensor ids."""
    return [*POSE_COLUMNS, *sensors]


class TraceWriter(BoundedFile):
    """An observer writing ``trace.csv`` (see the module doc) for these ``sensors`` (ids) at
    ``frame_rate`` steps a second."""

    def __init__(
        self,
        path: str | Path,
        sensors: Sequence[str],
        frame_rate: float,
        budget: RecordingBudget | None = None,
        on_stop: Callable[[str], None] | None = None,
    ) -> None:
        super().__init__(path, budget or RecordingBudget(), on_stop)
        self._made = 0
        """Rows made, written or waiting to be."""
        self.rows = 0
        """Rows in the file (without the header)."""
        self._column = {sensor: i for i, sensor in enumerate(sensors)}
        self._readings: list[float | None] = [None] * len(sensors)
        self._rows: list[str] = []
        """Rows (each in two pieces) made since the last flush: written together, once a
        simulated or a wall-clock second (a write per row costs more than making it)."""
        self._readings_text = "," * len(sensors) + "\n"
        """The end of a row: the readings, written again only when one changes."""
        self._changed = False
        self._columns_of: dict[str, tuple[tuple[int, int], ...]] = {}
        self._rows_per_step = min(1.0, TRACE_RATE / frame_rate)
        self._held_pieces = 2 * max(1, math.floor(min(TRACE_RATE, frame_rate) * HELD_SECONDS))
        """Pieces of :attr:`_rows` (two a row) that make :data:`HELD_SECONDS`: then they are
        written."""
        self._next_row = 0
        """The step that writes the next row."""
        self._collisions = 0
        self._last: StepEvent | None = None
        self._flush_at = time.monotonic() + FLUSH_INTERVAL
        self.resets = 0
        """Resets seen (each puts the time back to 0)."""
        self._write(",".join(trace_columns(sensors)) + "\n", 0)

    def begin(self, time_s: float, step: int, pose: Pose) -> None:
        """Write the row of the state the run starts from (before its first step)."""
        self._row(time_s, step, pose)

    def __call__(self, event: Event) -> None:
        """Observe one event: a step may make a row; commands, collisions and resets change
        what the next row says."""
        if type(event) is StepEvent:
            if event.step >= self._next_row:
                self._row(event.time, event.step, event.pose)
                self._last = None
            else:
                self._last = event
        elif isinstance(event, CommandEvent):
            self._command(event)
        elif isinstance(event, CollisionEvent):
            self._collisions += 1
        elif isinstance(event, ResetEvent):
            self.resets += 1
            self._collisions = 0
            self._readings = [None] * len(self._readings)
            self._changed = True
            self._next_row = 0
            self._last = None

    def _command(self, event: CommandEvent) -> None:
        """Keep the reply of each command addressed to a sensor."""
        columns = self._columns_of.get(event.message)
        if columns is None:
            ids = command_ids(event.message)
            columns = tuple(
                (i, self._column[d])
                for i, d in enumerate(_reading_columns(event.message, ids, self._column))
                if d in self._column
            )
            if len(self._columns_of) >= MAX_MESSAGES:
                self._columns_of.clear()
            self._columns_of[event.message] = columns
        replies = event.replies
        for reply, column in columns:
            if reply < len(replies):
                self._readings[column] = replies[reply]
                self._changed = True

    def _row(self, time_s: float, step: int, pose: Pose) -> None:
        if self._closed or self.stopped:  # a simulation thread that outlived the run
            return
        if self._changed:
            self._changed = False
            self._readings_text = (
                "".join(["," if v is None else "," + NUMBER % v for v in self._readings]) + "\n"
            )
        self._rows.append(ROW % (time_s, step, pose.x, pose.y, pose.heading, self._collisions))
        self._rows.append(self._readings_text)
        # the first step of the next 1/30 s: one whose step x rate reaches the next whole number
        tick = math.floor(step * self._rows_per_step + 1e-6)
        self._next_row = math.ceil((tick + 1 - 1e-6) / self._rows_per_step)
        self._made += 1
        if len(self._rows) >= self._held_pieces or time.monotonic() >= self._flush_at:
            self._flush()

    def _flush(self) -> None:
        """Write the rows made since the last flush, in one write; they are let go of before
        it, so that a flush cut short (by an exception) cannot write them a second time."""
        rows, self._rows = self._rows, []
        if rows:
            self._write("".join(rows), self._made - self.rows)
        self._flush_at = time.monotonic() + FLUSH_INTERVAL

    def _write(self, text: str, rows: int) -> None:
        """Write ``rows`` whole rows (``text``) if they fit the budget and the disk; else stop."""
        if self._put(text.encode("utf-8")):
            self.rows += rows

    def stop(self, reason: str) -> None:
        """Write nothing more (the rows held are dropped), cutting the file back to its last
        whole row, and say why (again: nothing)."""
        self._rows.clear()
        super().stop(reason)

    def close(self) -> None:
        """Write the last step's row if it has none yet, and close the file (again: nothing)."""
        if self._closed:
            return
        if self._last is not None:
            self._row(self._last.time, self._last.step, self._last.pose)
        self._flush()
        self._close_file()
