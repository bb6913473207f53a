"""Keeping runs: a run folder with the manifest, events, trace and report of one run.

See :mod:`simmer.record.runfolder` for the folder, :mod:`simmer.record.eventlog` for
``events.jsonl``, :mod:`simmer.record.trace` for ``trace.csv``, :mod:`simmer.record.scans`
for a LiDAR's ``scans.csv``, and :mod:`simmer.record.reader` for reading them back.
"""

from simmer.record.eventlog import EventLog
from simmer.record.reader import read_events, read_scans
from simmer.record.runfolder import (
    LoadedRun,
    RunRecorder,
    load_run,
    read_manifest,
    retrace,
    write_report_md,
)
from simmer.record.trace import TRACE_RATE, TraceWriter

__all__ = [
    "TRACE_RATE",
    "EventLog",
    "LoadedRun",
    "RunRecorder",
    "TraceWriter",
    "load_run",
    "read_events",
    "read_manifest",
    "read_scans",
    "retrace",
    "write_report_md",
]
