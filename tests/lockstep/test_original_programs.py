"""Programs written for the original SimMeR, unchanged, under ``simmer run --program`` (issue
17): the lockstep clock takes every message a program wrote before it sleeps, reads the clock
or opens a reply connection, so a program that sends on one connection and then sleeps gives
the same run every time; and each reply connection gets what that release sent.

What the originals sent, from their ``interface/communication.py`` and main loop (BEHAVIOUR
§6.4): v1.0/v1.1 fill the transmit buffer only while it is empty (``set_buffer_tx``), so a
second reply waiting behind the first is dropped; v1.2 appends every reply to the buffer and a
reply connection gets all of it in one frame (``make_tx_packet``); in every release a reply
connection with nothing waiting is closed at once, with nothing sent.
"""

from __future__ import annotations

import csv
import dataclasses
import hashlib
import shutil
import subprocess
import sys
from pathlib import Path
from typing import Any

import pytest

from link_support import run_program
from simmer import Simulation, runner
from simmer.record.eventlog import event_line
from simmer.sweep import run_sweep, sweep_from_dict
from simmer.world.events import CommandEvent, Event, RunEvent

from helpers import REPO, SIMMER_PY, make_config, noisy_data

pytestmark = pytest.mark.timeout(300)

STUDENT = REPO / "tests" / "fixtures" / "students" / "two_port_program.py"
RELEASES: dict[str, dict[str, Any]] = {
    "1.0": {"reply_bytes": 8},
    "1.1": {"reply_bytes": 4},
    "1.2": {"protocol": "framed", "str_encoding": "ascii"},
}
"""The reply format of each original release, as its configuration sets it."""


class EventHash:
    """A hash of every event of a run, each as ``events.jsonl`` writes it, with the client's
    port (which the operating system chooses) left out."""

    def __init__(self, sim: Simulation) -> None:
        self.digest = hashlib.sha256()
        self.count = 0
        sim.add_observer(self)

    def __call__(self, event: Event) -> None:
        if isinstance(event, CommandEvent):
            event = dataclasses.replace(event, client=event.client.split(" ")[0])
        self.digest.update(event_line(event).encode())
        self.count += 1


def run_student_program(pattern: str, release: str, capfd: pytest.CaptureFixture[str]) -> str:
    """Run the program unchanged on the lockstep clock; what it printed and the event hash."""
    sim = Simulation(make_config(noisy_data() | RELEASES[release]), seed=11)
    events = EventHash(sim)
    served = run_program(sim, f"{sys.executable} {STUDENT} {pattern} {release}")
    printed = capfd.readouterr().out
    assert (served.ended_by, served.exit_status) == ("program", 0), printed
    assert printed.endswith("done\n")
    return f"{printed}{events.count} events {events.digest.hexdigest()}"


@pytest.mark.slow
@pytest.mark.parametrize("release", list(RELEASES))
@pytest.mark.parametrize("pattern", ["dead_reckoning", "two_sends", "two_receives"])
def test_an_original_program_runs_unchanged_and_the_same_every_time(
    pattern: str, release: str, busy_cpu: None, capfd: pytest.CaptureFixture[str]
) -> None:
    runs = [run_student_program(pattern, release, capfd) for _ in range(3)]
    assert runs[0] == runs[1] == runs[2]


def test_a_message_sent_before_a_sleep_is_taken_before_the_sleep(
    capfd: pytest.CaptureFixture[str],
) -> None:
    # The program sends u0 on a connection of its own, then sleeps 0.1 s: u0 is read at the
    # start, whichever of the two reached the simulator first, and the move after it when
    # the sleep is over (one step per message on the lockstep clock).
    sim = Simulation(make_config(noisy_data()), seed=11)
    seen: list[Event] = []
    sim.add_observer(seen.append)
    run_program(sim, f"{sys.executable} {STUDENT} dead_reckoning 1.1")
    capfd.readouterr()
    taken = [(e.step, e.message) for e in seen if isinstance(e, CommandEvent)]
    assert taken[:2] == [(0, "u0"), (7, "w0-12")]
    clock = [(e.step, e.value) for e in seen if isinstance(e, RunEvent) and e.what == "clock"]
    assert clock[0] == (1, pytest.approx(0.1))


@pytest.mark.slow
def test_a_program_that_never_ends_its_line_is_not_waited_for_long(
    tmp_path: Path, caplog: pytest.LogCaptureFixture, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setattr(runner, "SYNC_WAIT", 0.2)  # the wait itself, not its 5 s, is tested
    program = tmp_path / "partial.py"
    program.write_text(
        "import os, socket, time\n"
        "s = socket.create_connection(('127.0.0.1', 61202))\n"
        "s.sendall(b'u0')  # no end of line: never a whole message\n"
        "time.sleep(0.5)\n"
        "print('slept', time.monotonic())\n",
        encoding="utf-8",
    )
    sim = Simulation.from_config()
    served = run_program(sim, f"{sys.executable} {program}", timeout=60)
    assert (served.ended_by, served.exit_status) == ("program", 0)
    assert "2 byte(s) the program wrote before 'sleep' never arrived" in caplog.text
    assert sim.time == pytest.approx(0.5, abs=sim.dt)


READ_BEFORE_CLOSING = """
import socket, sys
for index in range(6):
    with socket.create_connection(('127.0.0.1', 61200)) as out:
        out.sendall([b'u1', b'u0,u1'][index % 2])
        with socket.create_connection(('127.0.0.1', 61201)) as back:
            reply = back.recv(1024)
    if len(reply) != 4 * (index % 2 + 1):
        sys.exit(f'message {index}: {reply!r} is not its reply')
print('done')
"""
"""Reads each reply before it closes its send connection."""


def test_a_program_that_reads_before_closing_its_send_connection_is_not_held_up(
    tmp_path: Path,
    caplog: pytest.LogCaptureFixture,
    monkeypatch: pytest.MonkeyPatch,
    capfd: pytest.CaptureFixture[str],
) -> None:
    # Its message is taken when its reply connection is accepted, so the shim's sync before
    # the reply connection leaves it out instead of waiting SYNC_WAIT for it.
    monkeypatch.setattr(runner, "SYNC_WAIT", 0.5)
    program = tmp_path / "read_before_closing.py"
    program.write_text(READ_BEFORE_CLOSING, encoding="utf-8")
    served = run_program(Simulation.from_config(), f"{sys.executable} {program}", timeout=60)
    printed = capfd.readouterr()
    assert (served.ended_by, served.exit_status) == ("program", 0), printed.err
    assert printed.out == "done\n"
    assert "never arrived" not in caplog.text


@pytest.mark.slow
def test_a_sweep_of_a_send_then_sleep_program_is_the_same_at_any_worker_count(
    tmp_path: Path,
) -> None:
    shutil.copy(STUDENT, tmp_path)
    spec = sweep_from_dict(
        {
            "config": str(REPO / "examples" / "lab1_rover.toml"),
            "program": f"python {STUDENT.name} dead_reckoning 1.1",
            "seeds": 3,
            "grid": {"drives.w0.error.y": [0.02, 0.1], "drives.r0.error.rotation": [0.05]},
            "keep": "nothing",
        },
        tmp_path,
    )
    run_sweep(spec, tmp_path / "one", workers=1)
    run_sweep(spec, tmp_path / "two", workers=2)
    one = without_wall_time(read_table(tmp_path / "one" / "results.csv"))
    assert len(one) == 6
    assert {row["status"] for row in one} == {"ok"}
    assert len({row["final_x"] + row["final_y"] for row in one}) == 6  # noise: each its own
    assert without_wall_time(read_table(tmp_path / "two" / "results.csv")) == one

    table = tmp_path / "two" / "results.csv"  # a sweep stopped after its first three runs
    lines = table.read_text(encoding="utf-8").splitlines(keepends=True)
    table.write_text("".join(lines[:4]), encoding="utf-8")
    assert run_sweep(spec, tmp_path / "two", workers=2, resume=True).ran == 3
    assert without_wall_time(read_table(table)) == one


def read_table(path: Path) -> list[dict[str, str]]:
    with path.open(encoding="utf-8", newline="") as file:
        return list(csv.DictReader(file))


def without_wall_time(rows: list[dict[str, str]]) -> list[dict[str, str]]:
    return [{k: v for k, v in row.items() if k != "wall_time"} for row in rows]


@pytest.mark.slow
def test_the_originals_dead_reckoning_idea_prints_the_same_three_times(busy_cpu: None) -> None:
    # The issue's report: `simmer run config.py --headless --program "python3 -u
    # dead_reckoning.py"` with drive error on printed other readings each run.
    command = [
        sys.executable, "-m", "simmer", "run", str(SIMMER_PY / "lab_rover_noisy.py"),
        "--headless", "--program", f"{sys.executable} -u {STUDENT} dead_reckoning 1.0",
    ]  # fmt: skip
    printed = []
    for _ in range(3):
        done = subprocess.run(command, capture_output=True, text=True, timeout=120, check=False)
        assert done.returncode == 0, done.stderr
        lines = done.stdout.splitlines()
        start = next(i for i, line in enumerate(lines) if line.startswith("Ultrasonic 0"))
        printed.append(lines[start:-1])  # the program's printout and the outcome; not the log
    ended = next(i for i, line in enumerate(printed[0]) if line.startswith("outcome after"))
    assert printed[0][ended - 1].startswith("done")  # the program's last line, then the outcome
    assert printed[0] == printed[1] == printed[2]
