"""``scans.csv``: every whole scan of a run's LiDARs, beside ``trace.csv``.

One row per scan: ``time`` (simulated seconds when its revolution ended), ``step`` (the step
after which it was seen), ``device`` (the LiDAR's id), ``scan`` (its number: 1 the scan made at
the start pose, then one a revolution), then three cells of space-separated numbers, one per
beam in order of angle (beam k at k · 360 / beams degrees clockwise from the LiDAR's front):
``distances`` (inches, as the program reads them: 0 for no return), ``x`` and ``y`` (where the
beam met something, world inches; ``nan`` for no return). Three decimals (a thousandth of an
inch, twenty times finer than the noise) keep a 360-beam scan near 8 KB.

Why a file of its own: a scan is hundreds of numbers at 5.5 a second, a trace row a dozen at
30; columns per beam would not fit a trace of several LiDARs, and the events hold only the
beams a program read. The scans are what the device measured (noise, dropouts, motion skew),
read from it by this observer in the simulation's thread, so recording draws nothing and a
replay of the run writes the same file byte for byte.

Bounded: at most :data:`MAX_SCAN_BYTES` (then the file stops at its last whole row, the run
and its other files go on, and :attr:`ScanWriter.stopped` says why), outside the events' and
trace's budget so that scans never cut a replayable recording short. Read back only by
:func:`simmer.record.reader.read_scans`.
"""

from __future__ import annotations

import functools
from collections.abc import Callable
from pathlib import Path

import numpy as np

from simmer.devices.lidar import Lidar
from simmer.record.eventlog import BoundedFile, RecordingBudget
from simmer.world.events import Event, ResetEvent, StepEvent
from simmer.world.simulation import Simulation

MAX_SCAN_BYTES = 64 * 1024 * 1024
"""Bytes a recording's scans file holds: some 7,400 scans of 360 beams, 22 simulated minutes
of one LiDAR at 5.5 Hz (the lab's tasks take a few)."""
SCAN_COLUMNS = ("time", "step", "device", "scan", "distances", "x", "y")
"""The header row."""


def lidar_ids(sim: Simulation) -> list[str]:
    """The ids of the simulation's LiDARs, in configuration order."""
    return [i for i, d in sim.robot.sensors.items() if isinstance(d, Lidar)]


def _cell(values: np.ndarray) -> str:
    """Numbers as one cell: three decimals, space-separated (``nan`` as itself). One
    ``%`` of a format made once per length: half the time of formatting each number alone
    (a recorded scan is some thousand numbers), the same text."""
    return _cell_format(values.shape[0]) % tuple(values.tolist())


@functools.cache
def _cell_format(count: int) -> str:
    """``%.3f`` ``count`` times, space-separated (one a LiDAR's beam count: a few at most)."""
    return " ".join(["%.3f"] * count)


class ScanWriter(BoundedFile):
    """An observer writing ``scans.csv`` (see the module doc) for ``sim``'s LiDARs: after each
    step, the scans made since the last one. ``on_stop`` is told why if the file stops."""

    def __init__(
        self,
        path: str | Path,
        sim: Simulation,
        max_bytes: int = MAX_SCAN_BYTES,
        on_stop: Callable[[str], None] | None = None,
    ) -> None:
        budget = RecordingBudget(max_bytes, "MAX_SCAN_BYTES; the run's other files go on")
        told = None if on_stop is None else lambda why: on_stop(f"{Path(path).name} stopped: {why}")
        super().__init__(path, budget, told)
        self.sim = sim
        self.scans = 0
        """Scans in the file."""
        self._lidars: list[tuple[str, Lidar]] = []
        self._seen: dict[str, int] = {}
        self._find()
        self._write(",".join(SCAN_COLUMNS) + "\n", 0)

    def _find(self) -> None:
        """The LiDARs of the simulation as it is now (a reset builds them anew)."""
        sensors = self.sim.robot.sensors
        self._lidars = [(i, d) for i, d in sensors.items() if isinstance(d, Lidar)]
        self._seen = dict.fromkeys(sensors, 0)

    def __call__(self, event: Event) -> None:
        """After a step, write each LiDAR's scan if it is a new one; after a reset, look the
        LiDARs up again (their scans count from 1 again)."""
        if type(event) is StepEvent:
            rows = []
            for device_id, lidar in self._lidars:
                if lidar.number != self._seen[device_id]:
                    self._seen[device_id] = lidar.number
                    rows.append(
                        f"{lidar.scan_time:.10g},{event.step},{device_id},{lidar.number},"
                        f"{_cell(lidar.distances)},{_cell(lidar.points[:, 0])},"
                        f"{_cell(lidar.points[:, 1])}\n"
                    )
            if rows:
                self._write("".join(rows), len(rows))
        elif isinstance(event, ResetEvent):
            self._find()

    def _write(self, text: str, scans: int) -> None:
        """Write whole rows if they fit :data:`MAX_SCAN_BYTES` and the disk; else stop."""
        if not self._closed and self._put(text.encode("ascii")):
            self.scans += scans

    def close(self) -> None:
        """Close the file (again: nothing)."""
        if not self._closed:
            self._close_file()
