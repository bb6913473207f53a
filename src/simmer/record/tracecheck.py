"""Where a re-simulated run first differs from its recording: two ``trace.csv`` files compared.

Rows are matched by the step they were written at (and how many resets came before it), and
compared cell by cell as text: the same run writes the same digits, so any change of a pose or
a reading shows (:mod:`simmer.record.trace` writes 10 significant digits). A recording cut
short (``kill -9``) is compared as far as it goes; its last line, if it was cut in the middle,
is left out. The files are read by :func:`simmer.record.reader.read_trace_rows`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

STEP, TIME = "step", "time"
NO_ROW = "no row"

RowKey = tuple[int, int]
"""(resets before the row, step): where a row was written."""


@dataclass(frozen=True)
class TraceDifference:
    """The first cell where two traces differ (``column`` "row": one has a row the other has
    not; "columns": their headers differ)."""

    time: float
    """Simulated seconds in the trace (counted again from 0 after a reset)."""
    part: int
    """Resets before it."""
    column: str
    recorded: str
    replayed: str

    def describe(self) -> str:
        """In words: ``at 3.467 s in column x: recorded 12.5, re-simulated 12.6``."""
        after = f" (after reset {self.part})" if self.part else ""
        recorded = self.recorded or "blank"
        replayed = self.replayed or "blank"
        if self.column == "columns":
            return f"the trace columns differ: recorded {recorded}, re-simulated {replayed}"
        where = "" if self.column == "row" else f" in column {self.column}"
        return f"at {self.time:.3f} s{after}{where}: recorded {recorded}, re-simulated {replayed}"


@dataclass(frozen=True)
class TraceRows:
    """A trace's header and its whole rows, each with where it was written."""

    header: list[str]
    rows: list[tuple[RowKey, list[str]]]

    @property
    def end(self) -> RowKey | None:
        """Where the last row was written (None: no rows)."""
        return self.rows[-1][0] if self.rows else None

    @property
    def end_time(self) -> float:
        """The time of the last row, counted from the last reset before it (NaN: no rows, or
        not a number)."""
        return _time(self.rows[-1][1], self.header) if self.rows else math.nan


def _time(row: list[str], header: list[str]) -> float:
    try:
        return float(row[header.index(TIME)])
    except ValueError:
        return math.nan


def first_difference(
    recorded: TraceRows, replayed: TraceRows, *, complete: bool = True
) -> TraceDifference | None:
    """The first difference of ``replayed`` from ``recorded``, in ``replayed``'s order; None
    if they are the same. ``complete``: False if the recording was cut short, so that rows
    after its end are not differences."""
    header = replayed.header
    if recorded.header != header:
        return TraceDifference(0.0, 0, "columns", ",".join(recorded.header), ",".join(header))
    recorded_at = dict(recorded.rows)
    end = recorded.end
    for key, row in replayed.rows:
        old = recorded_at.get(key)
        if old is None:
            if not complete and (end is None or key > end):
                break
            return TraceDifference(_time(row, header), key[0], "row", NO_ROW, f"step {key[1]}")
        for name, was, now in zip(header, old, row, strict=True):
            if was != now:
                return TraceDifference(_time(row, header), key[0], name, was, now)
    replayed_keys = {key for key, _ in replayed.rows}
    for key, row in recorded.rows:
        if key not in replayed_keys:
            return TraceDifference(_time(row, header), key[0], "row", f"step {key[1]}", NO_ROW)
    return None


def cut_short(events_end: float | None, trace_end: float | None, untraced: int) -> str:
    """What a run folder without ``report.json`` (its run was killed, crashed, or lost power:
    the recorder writes the report however else the run ends) says about where it ends:
    ``events_end`` and ``trace_end`` in seconds from the run's start (None: no events, no
    trace rows), ``untraced`` the events after the trace's last row. The trace is written a
    simulated second at a time (:mod:`simmer.record.trace`), every event as it comes, so the
    events can go further: said, so that "matches" or a short plot is not read as the run."""
    ends = [end for end in (events_end, trace_end) if end is not None]
    at = f" at {max(ends):.2f} s" if ends else " at its start"
    events = "no events" if events_end is None else f"events to {events_end:.2f} s"
    trace = "no trace rows" if trace_end is None else f"trace to {trace_end:.2f} s"
    have = "event has" if untraced == 1 else "events have"
    return f"the run was cut short{at} ({events}, {trace}): {untraced:,} {have} no trace rows"
