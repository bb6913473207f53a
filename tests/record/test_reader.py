"""The one reader of a run folder's recordings (``simmer.record.reader``): what it gives back
of a damaged file, and its one error, a line naming the file."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from simmer.errors import RunFolderError, SimmerError
from simmer.record.reader import (
    EVENTS,
    TRACE,
    event_objects,
    read_events,
    read_trace,
    read_trace_rows,
)
from simmer.world.events import CommandEvent

COMMAND = '{"type":"command","time":0.5,"message":"u0","replies":[1.0],"step":30,"client":"x"}\n'


def test_a_trace_cut_before_its_newline_loses_its_last_line(tmp_path: Path) -> None:
    path = tmp_path / TRACE
    path.write_text("time,step,x\n0,0,1.5\n0.1,6,2.5\n0.2,12,3.")
    table = read_trace(path)
    assert (table.header, table.rows) == (
        ["time", "step", "x"],
        [["0", "0", "1.5"], ["0.1", "6", "2.5"]],
    )
    assert read_trace_rows(path).end == (0, 6)


def test_events_read_strictly_or_leniently(tmp_path: Path) -> None:
    path = tmp_path / EVENTS
    path.write_text(COMMAND + "[1]\nnot json\n" + COMMAND[:20])
    assert [number for number, _ in event_objects(path)] == [1]
    with pytest.raises(RunFolderError, match=r"events\.jsonl line 2: list, not a JSON object"):
        read_events(path)
    path.write_text(COMMAND + COMMAND[:20])  # a last line cut short is left out
    assert [type(event) for event in read_events(path)] == [CommandEvent]


@pytest.mark.parametrize("name", [EVENTS, TRACE])
def test_every_failure_is_one_error_naming_the_file(tmp_path: Path, name: str) -> None:
    path = tmp_path / name
    readers = [read_events, read_trace, read_trace_rows, lambda p: list(event_objects(p))]
    for read in readers:  # no such file
        with pytest.raises(RunFolderError, match=f"^cannot read {re.escape(str(path))}: "):
            read(path)
    path.write_bytes(b"time,step\n\xff\xfe,1\n")  # not UTF-8
    for read in (read_events, read_trace, read_trace_rows):
        with pytest.raises(
            RunFolderError, match=f"^cannot read {re.escape(str(path))}: 'utf-8' codec"
        ):
            read(path)
    path.write_text("time,x\n")
    with pytest.raises(
        RunFolderError, match=f"^cannot read {re.escape(str(path))}: .* has no step column$"
    ):
        read_trace_rows(path)
    assert issubclass(RunFolderError, SimmerError)
    assert issubclass(RunFolderError, ValueError)  # as the readers' errors were
