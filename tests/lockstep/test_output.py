"""A program's printout passing through SimMeR (simmer.lockstep.output): a prompt shows before
the program waits for its answer, a last line left open is ended once, and text reads right on
a terminal of another encoding. Real processes and pipes."""

from __future__ import annotations

import io
import os
import subprocess
import sys

import pytest

from simmer.lockstep.output import ProgramOutput

from helpers import wait_for

pytestmark = [pytest.mark.slow, pytest.mark.timeout(60)]

PROMPTING = """\
import sys
print('Starting')
zone = input('Which zone? ')
print('Going to', zone)
print('Heading 180\\u00b0', file=sys.stderr)
print('no newline', end='')
"""


def terminal(encoding: str) -> io.TextIOWrapper:
    """A stand-in for SimMeR's stdout or stderr: text over bytes we can read back."""
    return io.TextIOWrapper(io.BytesIO(), encoding=encoding, newline="")


def written(target: io.TextIOWrapper) -> bytes:
    target.flush()
    buffer = target.buffer
    assert isinstance(buffer, io.BytesIO)
    return buffer.getvalue()


def start(code: str, stdin: int = subprocess.DEVNULL) -> subprocess.Popen[bytes]:
    return subprocess.Popen(
        [sys.executable, "-c", code],
        stdin=stdin,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        env={**os.environ, "PYTHONIOENCODING": "utf-8", "PYTHONUNBUFFERED": "1"},
    )


def test_a_prompt_shows_before_the_program_waits_and_the_last_line_is_ended() -> None:
    out, err = terminal("utf-8"), terminal("utf-8")
    process = start(PROMPTING, subprocess.PIPE)
    printout = ProgramOutput(process, out, err)
    wait_for(lambda: written(out).endswith(b"Which zone? "), "the prompt, before any answer")
    assert process.poll() is None  # still waiting for its answer
    assert process.stdin is not None
    with process.stdin:
        process.stdin.write(b"B2\n")
    assert process.wait(30) == 0
    printout.finish()
    assert written(out) == b"Starting\nWhich zone? Going to B2\nno newline\n"
    assert written(err) == "Heading 180\u00b0\n".encode()
    printout.finish()  # once only
    assert written(out).endswith(b"no newline\n")


def test_text_reads_right_on_a_terminal_of_another_encoding() -> None:
    out, err = terminal("cp1252"), terminal("ascii")
    process = start("print('180\\u00b0 ' * 20000 + 'end')")  # over a read: a character may be split
    printout = ProgramOutput(process, out, err)
    assert process.wait(30) == 0
    printout.finish()
    assert written(out) == ("180\u00b0 " * 20000 + "end\n").encode("cp1252")
    assert written(err) == b""
