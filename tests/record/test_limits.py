"""A recording is bounded and survives a full disk (issue 18, items 7 and 8): it stops at its
size limit or when the disk fills, saying "the recording in DIR stopped: ...", with the last
line of events.jsonl whole and trace.csv claiming no row it does not have; a recorded run has a
default simulated-time limit."""

from __future__ import annotations

import errno
import json
import os
import subprocess
import sys
import uuid
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest

from simmer import Simulation
from simmer.cli.run import _recorded_run_limits
from simmer.record import RunRecorder, read_events
from simmer.record.runfolder import MAX_RUN_SECONDS
from simmer.view.replay_model import Recording

from helpers import drive_noisily, noisy_config

pytestmark = pytest.mark.timeout(180)

SIMMER = Path(sys.executable).with_name("simmer")


class FullDisk:
    """A file that takes ``room`` bytes more, writing part of the write that fills it, then
    fails with ENOSPC as a full disk does."""

    def __init__(self, inner: Any, room: int) -> None:
        self.inner = inner
        self.room = room

    def write(self, data: bytes) -> int:
        if self.room <= 0:
            raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))
        part = bytes(data[: self.room])
        self.room -= len(part)
        return int(self.inner.write(part))


def check_files(folder: Path, rows: int) -> None:
    """Every line of events.jsonl whole and an event; trace.csv has ``rows`` whole rows."""
    text = (folder / "events.jsonl").read_text()
    assert text.endswith("\n")
    read_events(folder / "events.jsonl")  # every line is an event
    lines = (folder / "trace.csv").read_text().splitlines(keepends=True)
    assert all(line.endswith("\n") for line in lines)
    width = lines[0].count(",")
    assert all(line.count(",") == width for line in lines)
    assert len(lines) - 1 == rows


@pytest.mark.slow
@pytest.mark.parametrize("full", ["events", "trace"])
def test_a_full_disk_stops_the_recording_at_whole_lines_and_says_so(
    tmp_path: Path, full: str
) -> None:
    folder = tmp_path / "run"
    sim = Simulation(noisy_config(), seed=3)
    said: list[str] = []
    recorder = RunRecorder(sim, folder, on_stop=said.append)
    writer = recorder.events if full == "events" else recorder.trace
    writer._send = FullDisk(writer._file, 3000).write
    drive_noisily(sim)  # the run goes on after the recording stops
    recorder.close()
    assert said == [f"the recording in {folder} stopped: disk full"]
    report = json.loads((folder / "report.json").read_text())
    assert report["recording_stopped"] == said[0]
    assert report["trace_rows"] == recorder.trace.rows
    check_files(folder, recorder.trace.rows)
    check = Recording.load(folder).check
    assert check.matches
    assert check.incomplete is not None
    assert check.incomplete.startswith(f"incomplete recording: {said[0]}; replayed up to")
    assert check.rows <= recorder.trace.rows


def test_a_recording_stops_at_its_size_limit_naming_it(tmp_path: Path) -> None:
    folder = tmp_path / "run"
    sim = Simulation(noisy_config(), seed=3)
    said: list[str] = []
    with RunRecorder(sim, folder, max_bytes=20_000, on_stop=said.append) as recorder:
        drive_noisily(sim)
    assert len(said) == 1
    assert "stopped: it reached the size limit" in said[0]
    assert "--record-limit" in said[0]
    sizes = sum((folder / name).stat().st_size for name in ("events.jsonl", "trace.csv"))
    assert sizes <= 20_000
    check_files(folder, recorder.trace.rows)


@pytest.fixture
def small_disk(tmp_path: Path) -> Iterator[Path]:
    """A 192 KiB tmpfs, where this machine allows mounting one."""
    mount = tmp_path / "disk"
    mount.mkdir()
    if not sys.platform.startswith("linux") or os.geteuid() != 0:
        pytest.skip("mounting a small tmpfs needs Linux and root; the injected full disk stands")
    done = subprocess.run(
        ["mount", "-t", "tmpfs", "-o", "size=192k", f"simmer-{uuid.uuid4().hex[:8]}", mount],
        check=False,
        capture_output=True,
        text=True,
    )
    if done.returncode != 0:
        pytest.skip(f"cannot mount a tmpfs here: {done.stderr.strip()}")
    try:
        yield mount
    finally:
        subprocess.run(["umount", "-l", mount], check=False)


@pytest.mark.slow
def test_a_run_recording_onto_a_small_disk_keeps_serving(small_disk: Path, tmp_path: Path) -> None:
    program = tmp_path / "chatty.py"
    program.write_text(
        "from simmer.client import connect\n"
        "with connect() as robot:\n"
        "    for _ in range(6000):\n"
        "        robot.read('u0')\n"
        "print('the program finished')\n"
    )
    folder = small_disk / "run"
    done = subprocess.run(
        [SIMMER, "run", "--headless", "--record", folder, "--program", f"python {program}"],
        check=False,
        capture_output=True,
        text=True,
        timeout=150,
    )
    output = done.stdout + done.stderr
    assert done.returncode == 0, output  # the program's own status: it ran to its end
    assert "the program finished" in output
    assert f"the recording in {folder} stopped: disk full" in output
    assert "Traceback" not in output
    events = (folder / "events.jsonl").read_text()
    assert events.endswith("\n")
    read_events(folder / "events.jsonl")
    lines = (folder / "trace.csv").read_text().splitlines(keepends=True)
    assert all(line.endswith("\n") for line in lines)
    check = Recording.load(folder).check  # report.json may not fit: then it is "incomplete"
    assert check.matches
    assert check.rows <= len(lines) - 1
    assert check.incomplete is not None


def test_a_recorded_run_is_limited_to_an_hour_by_default(
    capsys: pytest.CaptureFixture[str],
) -> None:
    assert MAX_RUN_SECONDS == 3600  # docs/limits.md's figure
    assert _recorded_run_limits(None, None, "python robot.py") == (3600, 3600)
    said = capsys.readouterr().out
    assert "a recorded run stops at 3600 s of simulated time (--seconds changes it)" in said
    assert "a recorded program is stopped after 3600 s of wall time (--timeout changes it)" in said


@pytest.mark.slow
def test_a_recorded_run_stops_at_its_simulated_time_limit(tmp_path: Path) -> None:
    # The limit lowered to a minute in this run's process: an hour is 216,000 steps, 8 s of CPU.
    lowered = (
        "import simmer.record.runfolder as folder; folder.MAX_RUN_SECONDS = 60.0; "
        "from simmer.cli import main; main()"
    )
    folder = tmp_path / "run"
    done = subprocess.run(
        [
            sys.executable,
            "-c",
            lowered,
            "run",
            "--headless",
            "--record",
            folder,
            "--program",
            "python -c 'import time; time.sleep(1e9)'",
        ],
        check=False,
        capture_output=True,
        text=True,
        timeout=150,
    )
    assert done.returncode == 3, done.stdout + done.stderr  # the --seconds limit's status
    assert "a recorded run stops at 60 s of simulated time (--seconds changes it)" in done.stdout
    report = json.loads((folder / "report.json").read_text())
    assert report["ended_by"] == "seconds"
    assert report["duration"] == pytest.approx(60, abs=0.1)
