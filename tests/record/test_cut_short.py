"""A run killed with SIGKILL (issue 28, item 12): its trace misses at most a simulated second
of rows, and ``replay --check`` and ``plot`` say where its events and its trace end instead of
"matches (0 trace rows)" or "the run recorded nothing"."""

from __future__ import annotations

import contextlib
import csv
import json
import os
import re
import shutil
import signal
import subprocess
import sys
from pathlib import Path

import pytest
from typer.testing import CliRunner

from simmer.cli import app
from simmer.record.trace import HELD_SECONDS, TRACE_RATE

from helpers import wait_for

pytestmark = pytest.mark.slow  # each kills a real recorded run (3.3-3.7 CPU s)

LONG_SLEEPS = """\
import os, sys
from pathlib import Path
from simmer.client import connect

Path(sys.argv[1]).write_text(str(os.getpid()))
with connect() as robot:
    for turn in range(100_000):
        robot.drive("w0", 2 if turn % 2 else -2)
        robot.send("u0,u1")
        robot.sleep(5)
"""
"""A program whose every turn is 5 simulated seconds: a recording makes 150 trace rows a turn
(in well under a wall-clock second: the trace was written every 1,024 rows or wall second)."""

EVENTS = 300
"""Events written when the run is killed."""


@pytest.fixture(scope="module")
def killed_run(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The folder of ``simmer run --program ... --record`` killed with SIGKILL once its
    events.jsonl holds :data:`EVENTS` lines."""
    here = tmp_path_factory.mktemp("killed")
    program, folder, pid = here / "program.py", here / "run", here / "program.pid"
    program.write_text(LONG_SLEEPS, encoding="utf-8")
    command = [
        sys.executable, "-m", "simmer", "run", "--headless", "--port", "0", "--port-rx", "0",
        "--port-tx", "0", "--record", str(folder), "--program",
        f"{sys.executable} {program} {pid}",
    ]  # fmt: skip
    process = subprocess.Popen(command, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    events = folder / "events.jsonl"
    try:
        wait_for(
            lambda: events.exists() and events.read_bytes().count(b"\n") >= EVENTS,
            f"the recorded run to write {EVENTS} events",
            60,
        )
        os.kill(process.pid, signal.SIGKILL)
    finally:
        process.kill()
        process.wait(10)
        if pid.exists():  # its program, left without its simulator, ends at its next message
            with contextlib.suppress(ProcessLookupError):
                os.kill(int(pid.read_text()), signal.SIGKILL)
    assert process.returncode == -signal.SIGKILL
    assert not (folder / "report.json").exists()
    return folder


def _ends(folder: Path) -> tuple[float, float]:
    """The time of the last event and of the trace's last row (no reset in these runs)."""
    lines = (folder / "events.jsonl").read_text(encoding="utf-8").splitlines()
    events_end = json.loads(lines[-1])["time"]
    with (folder / "trace.csv").open(encoding="utf-8") as file:
        rows = list(csv.DictReader(file))
    return float(events_end), float(rows[-1]["time"]) if rows else 0.0


def test_a_killed_run_loses_at_most_a_simulated_second_of_trace(killed_run: Path) -> None:
    events_end, trace_end = _ends(killed_run)
    assert events_end > 100  # 300 events of a program sleeping 5 s a turn
    assert events_end - trace_end <= HELD_SECONDS + 1 / TRACE_RATE + 1e-6


def test_replay_check_says_where_a_killed_run_was_cut_short(killed_run: Path) -> None:
    events_end, trace_end = _ends(killed_run)
    result = CliRunner().invoke(app, ["replay", "--check", str(killed_run)])
    assert result.exit_code == 0, result.output
    assert "matches the recording as far as it goes" in result.output
    said = re.search(
        r"the run was cut short at ([\d.]+) s \(events to ([\d.]+) s, trace to ([\d.]+) s\): "
        r"([\d,]+) events? ha(?:s|ve) no trace rows; no report.json: the trace is compared up "
        r"to ([\d.]+) s",
        result.output,
    )
    assert said is not None, result.output
    at, events, trace, untraced, compared = said.groups()
    assert float(events) == pytest.approx(events_end, abs=0.005)
    assert float(trace) == float(compared) == pytest.approx(trace_end, abs=0.005)
    assert float(at) == max(float(events), float(trace))  # a sleep goes on past its event
    lines = (killed_run / "events.jsonl").read_text(encoding="utf-8").splitlines()
    assert int(untraced) == sum(json.loads(line)["time"] > trace_end for line in lines)


def test_plot_draws_a_killed_run_and_says_where_it_was_cut_short(
    killed_run: Path, tmp_path: Path
) -> None:
    folder = tmp_path / "run"
    shutil.copytree(killed_run, folder)
    result = CliRunner().invoke(app, ["plot", str(folder)])
    assert result.exit_code == 0, result.output
    assert "the run was cut short at" in result.output
    assert "the plots go to" in result.output
    assert (folder / "path.png").is_file()


def test_a_killed_run_without_trace_rows_is_not_said_to_have_recorded_nothing(
    killed_run: Path, tmp_path: Path
) -> None:
    """The trace as the old writer could leave it: killed before its first 1,024 rows."""
    folder = tmp_path / "run"
    shutil.copytree(killed_run, folder)
    trace = folder / "trace.csv"
    trace.write_text(trace.read_text(encoding="utf-8").splitlines()[0] + "\n", encoding="utf-8")
    events = len((folder / "events.jsonl").read_text(encoding="utf-8").splitlines())
    plotted = CliRunner().invoke(app, ["plot", str(folder)])
    assert plotted.exit_code == 1
    assert "recorded nothing" not in plotted.output
    assert f"events to {_ends(folder)[0]:.2f} s, no trace rows): {events:,} events" in (
        plotted.output
    )
    checked = CliRunner().invoke(app, ["replay", "--check", str(folder)])
    assert checked.exit_code == 0, checked.output
    assert "(0 trace rows" in checked.output
    assert "every reply is compared, the trace is not" in checked.output
