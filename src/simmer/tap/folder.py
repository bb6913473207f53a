"""A tap's run folder: the real run, as ``simmer plot``, ``simmer replay``, ``simmer calibrate``
and ``simmer compare`` read it.

The same files as a simulated run's, where they mean the same, and no more:

- ``manifest.json``: ``"kind": "tap"``, the configuration the tap decoded with (as a
  simulated run's manifest holds it, so the maze and the devices are known), the robot's port,
  the wall-clock start (ISO and Unix seconds), and ``"true_pose": false``: a real run has no
  true pose, and no seed;
- ``events.jsonl``: a ``command`` event per exchange, in the order the program sent them;
  ``time`` is wall-clock seconds since the tap started (when the message's last byte passed),
  ``client`` is ``"tap"``, and a command the robot never answered has NaN;
- ``exchanges.csv``: the same exchanges with both wall times (sent, replied) and the reply as
  it came (its frame, or the packed bytes in hex);
- ``report.json``: how the tap ended (the robot lost or not), the exchanges, bytes each way.

No ``trace.csv``: there is no pose to trace.
"""

from __future__ import annotations

import csv
import io
import json
import math
import time
from dataclasses import dataclass
from datetime import datetime
from pathlib import Path
from typing import Any

import simmer
from simmer.config.models import SimConfig
from simmer.errors import SimmerError
from simmer.record.eventlog import EventLog
from simmer.record.reader import EVENTS, read_events
from simmer.record.runfolder import (
    FORMAT,
    MANIFEST,
    REPORT_JSON,
    config_from_manifest,
    config_to_manifest,
    read_manifest,
)
from simmer.record.safefile import check_target, write_text
from simmer.tap.decode import Exchange
from simmer.world.events import CommandEvent

TAP_KIND = "tap"
"""A tap's manifest's ``kind``."""
EXCHANGES = "exchanges.csv"
EXCHANGE_COLUMNS = ("sent", "replied", "message", "replies", "reply")
CLIENT = "tap"


def is_tap_folder(manifest: dict[str, Any]) -> bool:
    """Whether a run folder's manifest is a tap's (a real run: no true pose)."""
    return manifest.get("kind") == TAP_KIND


class TapRecorder:
    """Writes a tap's run folder (see the module doc); each exchange is on disk when
    :meth:`record` returns, so a tap that dies keeps what it saw."""

    def __init__(self, folder: str | Path, config: SimConfig, target: str) -> None:
        self.folder = Path(folder)
        self.folder.mkdir(parents=True, exist_ok=True)
        if (self.folder / MANIFEST).exists():
            raise ValueError(
                f"{self.folder} already holds a recorded run; record into a new folder, or "
                "delete it"
            )
        for name in (MANIFEST, EVENTS, EXCHANGES, REPORT_JSON):
            check_target(self.folder / name)
        self.config = config
        self.rate = config.settings.frame_rate
        self.start = time.time()
        self.started = datetime.now().astimezone()
        data = {
            "format": FORMAT,
            "kind": TAP_KIND,
            "simmer_version": simmer.__version__,
            "started": self.started.isoformat(timespec="seconds"),
            "started_unix": self.start,
            "target": target,
            "true_pose": False,
            "note": "a real run recorded by simmer tap: commands and replies with wall-clock "
            "times; no true pose and no seed",
            "seed": None,
            "clock": "wall",
            "program": None,
            "config": config_to_manifest(config),
        }
        write_text(self.folder / MANIFEST, json.dumps(data, indent=2) + "\n")
        self.events = EventLog(self.folder / EVENTS)
        self._csv = (self.folder / EXCHANGES).open("w", encoding="utf-8", newline="")
        self._csv.write(",".join(EXCHANGE_COLUMNS) + "\n")
        self._csv.flush()
        self.exchanges = 0

    def record(self, exchange: Exchange) -> None:
        """Write one exchange to events.jsonl and exchanges.csv."""
        sent = exchange.sent - self.start
        replies = tuple(exchange.replies)
        self.events(
            CommandEvent(sent, exchange.message, replies, step=int(sent * self.rate), client=CLIENT)
        )
        replied = "" if exchange.replied is None else f"{exchange.replied - self.start:.6f}"
        row = io.StringIO()
        csv.writer(row, lineterminator="\n").writerow(
            [
                f"{sent:.6f}",
                replied,
                exchange.message,
                " ".join("nan" if math.isnan(v) else repr(v) for v in replies),
                exchange.reply_text,
            ]
        )
        self._csv.write(row.getvalue())
        self._csv.flush()
        self.exchanges += 1

    def close(
        self,
        ended: str,
        robot_lost: bool,
        *,
        bytes_sent: int,
        bytes_received: int,
        stray: int,
        program: list[str] | None,
        program_status: int | None,
    ) -> None:
        """Close the files and write report.json."""
        self.events.close()
        self._csv.close()
        report = {
            "kind": TAP_KIND,
            "simmer_version": simmer.__version__,
            "ended": ended,
            "robot_lost": robot_lost,
            "duration": time.time() - self.start,
            "exchanges": self.exchanges,
            "bytes_sent": bytes_sent,
            "bytes_received": bytes_received,
            "stray_bytes": stray,
            "program": program,
            "program_status": program_status,
            "true_pose": False,
        }
        write_text(self.folder / REPORT_JSON, json.dumps(report, indent=2) + "\n")


@dataclass(frozen=True)
class TapRun:
    """A tap's run folder read back: the configuration it decoded with, and its exchanges
    in order (each a :class:`~simmer.world.events.CommandEvent`; ``time`` in wall seconds)."""

    folder: Path
    config: SimConfig
    exchanges: list[CommandEvent]
    manifest: dict[str, Any]


def load_tap_run(folder: str | Path) -> TapRun:
    """Read a tap's run folder (ValueError, one line naming the file, if it is not one: a
    simulated run's folder, a newer layout, a manifest or events that are not SimMeR's)."""
    folder = Path(folder)
    data = read_manifest(folder)
    where = folder / MANIFEST
    if not is_tap_folder(data):
        raise ValueError(
            f"{where}: not a tap's run folder (simmer tap --record DIR writes one of the real "
            "robot)"
        )
    try:
        config = config_from_manifest(data["config"])
    except (KeyError, TypeError, ValueError, AttributeError, SimmerError) as exc:
        raise ValueError(f"{where}: not a tap's manifest: {exc}") from None
    events = [e for e in read_events(folder / EVENTS) if isinstance(e, CommandEvent)]
    return TapRun(folder, config, events, data)
