"""Deep nesting in a belief (issue 28, item 4): ``%show`` with ``[`` x 3,000 raised
RecursionError in the loop, so the connection was closed with no reply and a 30-line traceback
was logged for every such message (not rate-limited); the same belief in ``events.jsonl`` ended
``replay --check`` and ``render`` in a RecursionError traceback. Now a bounded reader refuses
it with one plain line."""

from __future__ import annotations

import json
import math
import os
import signal
import socket
import subprocess
import sys
import time
from pathlib import Path

import pytest

from link_support import read_frame
from simmer.localize.belief import SHOWS_PER_SECOND
from simmer.runner import LOG_LINES_PER_SECOND
from simmer.untrusted import MAX_JSON_DEPTH

from helpers import FREE_PORTS, run_simmer

DISPLAYLESS = {**os.environ, "SDL_VIDEODRIVER": "dummy", "SDL_AUDIODRIVER": "dummy"}

pytestmark = pytest.mark.timeout(300)

DEEP = "[" * 3000


@pytest.mark.slow
@pytest.mark.usefixtures("ctrl_c")  # it ends the server with SIGINT
def test_deep_shows_are_answered_and_their_log_lines_bounded(tmp_path: Path) -> None:
    log = tmp_path / "simmer.log"
    command = [sys.executable, "-m", "simmer", "run", "--headless", "--speed", "max", *FREE_PORTS]
    with (
        log.open("w") as err,
        subprocess.Popen(
            command, stdout=subprocess.PIPE, stderr=err, text=True, env=DISPLAYLESS
        ) as server,
    ):
        try:
            assert server.stdout is not None
            for line in server.stdout:
                if line.startswith("persistent TCP"):
                    port = int(line.split(" port ")[1].split()[0])
                if line.startswith("running headless"):
                    break
            started = time.monotonic()
            with socket.create_connection(("127.0.0.1", port), timeout=30) as sock:
                message = f"%show {DEEP}\n".encode()
                sock.sendall(message)
                assert math.isnan(read_frame(sock)[0])  # refused, as other bad shows are
                replies = []
                for _ in range(50):  # 5,000 in all, in batches (the server reads 1,000 ahead)
                    sock.sendall(message * 100)
                    replies += [read_frame(sock) for _ in range(100)]
                sock.sendall(b"u0\n")
                assert read_frame(sock)[0] > 0  # still answering
            seconds = time.monotonic() - started
            assert all(len(r) == 1 and (math.isnan(r[0]) or r[0] == -1.0) for r in replies)
            # -1: over the shows a simulated second may keep; NaN: read and refused
            assert sum(math.isnan(r[0]) for r in replies) >= SHOWS_PER_SECOND - 1
        finally:
            server.send_signal(signal.SIGINT)
            server.wait(timeout=60)
    lines = log.read_text(encoding="utf-8").splitlines()
    assert not [line for line in lines if "Traceback" in line or "RecursionError" in line]
    refused = [line for line in lines if "MAX_JSON_DEPTH" in line]
    assert refused
    assert all(len(line) < 300 for line in refused)
    counted = [line for line in lines if "more log lines in one second" in line]
    assert len(refused) + len(counted) <= (LOG_LINES_PER_SECOND + 1) * (math.ceil(seconds) + 1)


def record(tmp_path: Path) -> Path:
    """A run folder whose events hold one shown belief."""
    program = tmp_path / "show.py"
    program.write_text(
        "from simmer.client import connect\n"
        "with connect() as robot:\n"
        "    robot.show(pose=(12, 12, 0), labels=[(12.0, 12.0, 'here')])\n"
        "    robot.sleep(0.1)\n",
        encoding="utf-8",
    )
    folder = tmp_path / "run"
    run = run_simmer(
        "run", "--headless", *FREE_PORTS, "--seconds", "1", "--program",
        f"{sys.executable} {program}", "--record", str(folder),
    )  # fmt: skip
    assert run.returncode == 0, run.stderr
    return folder


def rewrite_events(folder: Path, change: str) -> None:
    """Replace the belief event's belief (``"belief"``) or the whole line (``"line"``) with
    deep nesting."""
    path = folder / "events.jsonl"
    lines = path.read_text(encoding="utf-8").splitlines(keepends=True)
    for i, line in enumerate(lines):
        if '"type":"belief"' in line:
            event = json.loads(line)
            event["belief"] = DEEP
            text = json.dumps(event, separators=(",", ":"))
            lines[i] = text + "\n" if change == "belief" else DEEP + "\n"
    path.write_text("".join(lines), encoding="utf-8")


@pytest.mark.slow
def test_a_deep_belief_in_a_recording_is_one_plain_line(tmp_path: Path) -> None:
    folder = record(tmp_path)
    rewrite_events(folder, "belief")
    for command in (["replay", "--check"], ["render"]):
        done = run_simmer(*command, str(folder))
        assert done.returncode == 0, done.stderr
        assert "Traceback" not in done.stderr
        said = [line for line in done.stderr.splitlines() if "MAX_JSON_DEPTH" in line]
        assert len(said) == 1, done.stderr
        assert f"more than {MAX_JSON_DEPTH} deep" in said[0]
    assert (folder / "replay.mp4").stat().st_size > 0

    rewrite_events(folder, "line")
    for command in (["replay", "--check"], ["render", "-o", str(tmp_path / "clip.mp4")]):
        done = run_simmer(*command, str(folder))
        assert done.returncode != 0
        assert "Traceback" not in done.stderr
        lines = [line for line in done.stderr.splitlines() if line.strip()]
        assert len(lines) == 1, done.stderr
        assert "events.jsonl line" in lines[0]
        assert "MAX_JSON_DEPTH" in lines[0]
