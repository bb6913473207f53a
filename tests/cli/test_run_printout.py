"""``simmer run --program``'s printout reads the same every time (issue 30): the program's
lines and SimMeR's never share a line, and the end-of-run lines start on a line of their own,
however the program's output and the run's end fell in time.

The program (tests/fixtures/students/printing_program.py) prints as students' programs do: a
line finished after a sleep, lines on stderr, an ``input()`` prompt answered by ``--answer``,
and a last line with no newline; "stopped" makes it ask the simulator to stop (SIGTERM, as a
closed terminal does) in the middle of a line and wait to be stopped.
"""

from __future__ import annotations

import re
import subprocess
import sys
from collections.abc import Iterator
from contextlib import contextmanager

import pytest

from helpers import REPO, run_simmer

pytestmark = pytest.mark.skipif(sys.platform == "win32", reason="the program signals with SIGTERM")

PROGRAM = REPO / "tests" / "fixtures" / "students" / "printing_program.py"

PRINTED = [
    "Starting the run",
    *["Ultrasonic 0 reading: 39.5", "Driving... reply inf"] * 3,
    "Which zone? Going to B2",
    "Heading 180° (still)",
]
"""What the program prints on stdout in every run, up to its ending."""

ERRORS = [f"still at the start, turn {turn}" for turn in range(3)]

ENDINGS = {
    "": (["Done, and no newline"], [], "the program exited with status 0", 0),
    "stopped": (["stopping here"], ["stopped (SIGTERM)"], "the run was stopped", 0),
}
"""Per argument: the program's last stdout line (SimMeR ends it), SimMeR's lines said after
the program, how the run ended, the exit status."""


def run(argument: str) -> tuple[str, str, int]:
    """``simmer run --headless --program "python printing_program.py ARGUMENT" --answer B2``:
    its stdout and stderr, with this run's free ports and its log's random name written as
    ``PORT`` and ``LOG`` (chosen by the system, and random by design), and its status."""
    command = f"python {PROGRAM} {argument}".strip()
    done = run_simmer("run", "--headless", "--program", command, "--answer", "B2", timeout=120)

    def same(text: str) -> str:
        text = re.sub(r"(rx |tx |port )\d+", r"\1PORT", text)
        return re.sub(r"simmer-[\w]+\.log", "LOG", text)

    return same(done.stdout), same(done.stderr), done.returncode


def check(argument: str, stdout: str, stderr: str, status: int) -> None:
    """The printout is SimMeR's start-up lines, then exactly the program's lines (each whole,
    the last one ended by SimMeR), then SimMeR's end-of-run lines; stderr is the program's."""
    last, said, ended, expected_status = ENDINGS[argument]
    assert status == expected_status, stderr
    lines = stdout.split("\n")
    start = next(i for i, line in enumerate(lines) if line.startswith("starting the program: "))
    assert lines[start - 1] == "running headless, as fast as possible; Ctrl-C to stop"
    ours = lines[start + 1 + len(PRINTED) + len(last) :]
    assert lines[start + 1 : start + 1 + len(PRINTED) + len(last)] == PRINTED + last
    assert ours[: len(said)] == said
    assert ours[len(said)].startswith("outcome after ")
    assert ours[-2:] == [
        f"run ended: {ended}; the simulator's log had no warnings and is removed",
        "",
    ]
    assert stderr == "\n".join([*ERRORS, "an error with no newline", ""])


@contextmanager
def burning() -> Iterator[None]:
    """Another process keeping a CPU busy meanwhile (as the ``busy_cpu`` fixture, for part of
    a test)."""
    hog = subprocess.Popen([sys.executable, "-c", "while True: pass"])
    try:
        yield
    finally:
        hog.kill()
        hog.wait()


@pytest.mark.slow
def test_the_printout_is_the_same_every_run_and_never_mixes_lines() -> None:
    runs = [run("") for _ in range(3)]
    with burning():
        runs += [run("") for _ in range(2)]
    for stdout, stderr, status in runs:
        check("", stdout, stderr, status)
    assert all(printout == runs[0] for printout in runs)


@pytest.mark.slow
def test_a_run_stopped_mid_line_says_so_on_a_line_of_its_own(busy_cpu: None) -> None:
    runs = [run("stopped") for _ in range(2)]
    for stdout, stderr, status in runs:
        check("stopped", stdout, stderr, status)
    assert runs[0] == runs[1]
