"""``simmer tap``: a pyserial program talks to a second simulator's serial port through the tap
and sees exactly what it sees without it; the run folder holds every exchange in order; a tap
that loses its robot keeps what it recorded."""

from __future__ import annotations

import json
import math
import socket
import struct
import sys
import threading
from pathlib import Path

import pytest

from link_support import serving
from simmer.config import load_config
from simmer.errors import TapError
from simmer.record.reader import read_events
from simmer.tap.decode import TapDecoder
from simmer.tap.folder import is_tap_folder
from simmer.tap.session import Tap
from simmer.world.events import CommandEvent

pytestmark = pytest.mark.timeout(90)

PROGRAM = """\
import json, math, struct, sys, time
import serial

port = serial.Serial(sys.argv[1], 9600, timeout=10)
log = []

def send(message):
    port.write(message.encode() + b"\\n")
    data = port.read(4 * (message.count(",") + 1))
    values = [v for (v,) in struct.iter_unpack("<f", data)]
    log.append([message, [repr(v) for v in values]])
    return values

out = []
out.append(send("u0"))
out.append(send("u0,u1,u2,u3"))
out.append(send("w0-3"))
while not math.isinf(send("w0-0")[0]):
    time.sleep(0.02)
out.append(send("u0,u1,u2,u3"))
out.append(send("r0-90"))
while not math.isinf(send("w0-0")[0]):
    time.sleep(0.02)
out.append(send("u0,u1,u2,u3"))
out.append(send("zz"))
with open(sys.argv[2], "w") as f:
    for values in out:
        f.write(" ".join(repr(v) for v in values) + "\\n")
with open(sys.argv[3], "w") as f:
    json.dump(log, f)
"""


def _program(tmp_path: Path) -> Path:
    path = tmp_path / "robot_program.py"
    path.write_text(PROGRAM)
    return path


@pytest.mark.slow
def test_a_pyserial_program_sees_the_same_bytes_through_the_tap(tmp_path: Path) -> None:
    program = _program(tmp_path)
    config = load_config()
    with serving(serial=True) as (_, link):  # the program straight on the robot's port
        assert link.serial is not None
        import subprocess

        done = subprocess.run(
            [
                sys.executable,
                str(program),
                link.serial.path,
                tmp_path / "direct.txt",
                tmp_path / "direct.json",
            ],
            check=False,
            timeout=60,
        )
        assert done.returncode == 0
    with serving(serial=True) as (_, link):  # a second robot, the program through the tap
        assert link.serial is not None
        tap = Tap(config, link.serial.path, tmp_path / "real")
        result = tap.run(
            [
                sys.executable,
                str(program),
                "{port}",
                str(tmp_path / "tapped.txt"),
                str(tmp_path / "tapped.json"),
            ]
        )
    direct = (tmp_path / "direct.txt").read_bytes()
    assert (tmp_path / "tapped.txt").read_bytes() == direct
    assert b"nan" in direct
    assert b"inf" in direct
    assert result.ended.startswith("the program exited")
    assert not result.robot_lost
    # the run folder: every command and reply the program saw, in order
    seen = json.loads((tmp_path / "tapped.json").read_text())
    events = read_events(tmp_path / "real" / "events.jsonl")
    assert all(isinstance(e, CommandEvent) and e.client == "tap" for e in events)
    recorded = [
        [e.message, [repr(struct.unpack("<f", struct.pack("<f", v))[0]) for v in e.replies]]
        for e in events
        if isinstance(e, CommandEvent)
    ]
    assert recorded == seen
    times = [e.time for e in events]
    assert times == sorted(times)
    assert times[0] >= 0
    manifest = json.loads((tmp_path / "real" / "manifest.json").read_text())
    assert is_tap_folder(manifest)
    assert manifest["true_pose"] is False
    report = json.loads((tmp_path / "real" / "report.json").read_text())
    assert report["exchanges"] == len(seen)
    assert report["robot_lost"] is False
    assert report["stray_bytes"] == 0


def _one_answer_then_gone(server: socket.socket, replies: list[bytes | None]) -> None:
    """A robot on TCP that answers a line with each of ``replies``, then drops the link on
    the next line, unanswered."""
    conn, _ = server.accept()
    with conn:
        buffer = b""
        for reply in [*replies, None]:
            while b"\n" not in buffer:
                buffer += conn.recv(100)
            buffer = buffer.split(b"\n", 1)[1]
            if reply is not None:
                conn.sendall(reply)


def test_a_tap_that_loses_its_robot_keeps_what_it_recorded(tmp_path: Path) -> None:
    server = socket.create_server(("127.0.0.1", 0))
    port = server.getsockname()[1]
    robot = threading.Thread(target=_one_answer_then_gone, args=(server, [struct.pack("<f", 12.5)]))
    robot.start()
    tap = Tap(load_config(), f"tcp://127.0.0.1:{port}", tmp_path / "lost")
    script = tmp_path / "p.py"
    script.write_text(
        "import os, sys, time\n"
        "fd = os.open(sys.argv[1], os.O_RDWR)\n"
        "os.write(fd, b'u0\\n'); print(os.read(fd, 4))\n"
        "os.write(fd, b'u1\\n')\n"
        "time.sleep(30)\n"  # still running when the robot goes: the tap ends it
    )
    result = tap.run([sys.executable, str(script), "{port}"])
    robot.join()
    server.close()
    assert result.robot_lost
    assert "the robot was lost" in result.ended
    events = read_events(tmp_path / "lost" / "events.jsonl")
    assert next((e.message, e.replies) for e in events if isinstance(e, CommandEvent)) == (
        "u0",
        (12.5,),
    )
    last = events[-1]
    assert isinstance(last, CommandEvent)
    assert last.message == "u1"
    assert math.isnan(last.replies[0])  # sent, never answered: kept, with NaN
    report = json.loads((tmp_path / "lost" / "report.json").read_text())
    assert report["robot_lost"] is True
    assert "lost" in report["ended"]


def test_an_unreachable_robot_is_one_plain_error(tmp_path: Path) -> None:
    with pytest.raises(TapError, match="cannot open the robot's port"):
        Tap(load_config(), str(tmp_path / "no-such-port"), tmp_path / "run")
    assert not (tmp_path / "run").exists()


def test_packed_decoding_across_chunks_and_by_silence() -> None:
    decoder = TapDecoder("packed", 4)
    decoder.sent(b"u0,u", 0.0)
    decoder.sent(b"1\nw0-", 0.01)
    assert decoder.received(struct.pack("<f", 1.5), 0.02) == []  # half of u0,u1's reply
    [first] = decoder.received(struct.pack("<ff", 2.5, math.inf)[:4], 0.03)
    assert first.message == "u0,u1"
    assert first.replies == [1.5, 2.5]
    assert first.replied == 0.03
    decoder.sent(b"6", 0.04)
    decoder.quiet(0.06)  # not yet 50 ms of quiet
    assert len(decoder.waiting) == 0
    decoder.quiet(0.10)
    [second] = decoder.received(struct.pack("<f", math.inf), 0.11)
    assert second.message == "w0-6"
    assert second.replies == [math.inf]
    assert second.sent == 0.04


def test_framed_decoding_skips_text_outside_frames_and_pairs_in_order() -> None:
    decoder = TapDecoder("framed")
    decoder.sent(b"hello[u0,w0:6]\n[u", 0.0)
    decoder.sent(b"1]", 0.1)
    assert decoder.stray == len(b"hello") + 1
    done = decoder.received(b"[u0:15.45,w0:True][u1:Not", 0.2)
    assert [(d.message, d.replies) for d in done] == [("u0,w0:6", [15.45, math.inf])]
    [last] = decoder.received(b" Found]", 0.3)
    assert last.message == "u1"
    assert math.isnan(last.replies[0])
    assert last.reply_text == "u1:Not Found"
