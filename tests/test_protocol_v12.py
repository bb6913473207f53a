"""SimMeR v1.2's framed text protocol, v1.0 reply widths and the originals' lenient parsing,
over real loopback sockets and a real pseudo-terminal (BEHAVIOUR §6.1 and §6.2).

The expected replies are written out as the original v1.2 sends them for the default maze and
lab rover (noise off): u0 reads 39.5 in, u1 3.5 in, u2 53.588425... in (53.588 at 3 decimals).
"""

from __future__ import annotations

import logging
import math
import socket
import struct
import subprocess
import sys
from pathlib import Path

import pytest
import serial

from link_support import serving, two_port_raw, two_port_send
from simmer import Simulation
from simmer.client import connect
from simmer.config import load_config
from simmer.console import run_console
from simmer.protocol import (
    MAX_SHOWN,
    CommandText,
    FramedCodec,
    first_frame,
    framed_value,
    parse_command,
    unwrap_frames,
)

from helpers import SIMMER_PY, default_data, make_config, wait_for

pytestmark = pytest.mark.timeout(60)


def framed_sim(**settings: object) -> Simulation:
    """The default maze and rover, speaking SimMeR v1.2's framed text (native settings)."""
    data = default_data() | {"protocol": "framed", "str_encoding": "ascii"} | settings
    return Simulation(make_config(data))


# ----------------------------------------------------------------------------- pure


@pytest.mark.parametrize(
    ("text", "commands"),
    [
        ("[u0]", "u0"),
        ("[u0][u1]", "u0,u1"),
        ("hello [u0,w0:6] bye", "u0,w0:6"),
        ("[u0]junk[u1]\n", "u0,u1"),
        ("u0", None),
        ("[u0", None),
        ("u0]", None),
    ],
)
def test_frames_are_unwrapped_and_text_outside_them_ignored(
    text: str, commands: str | None
) -> None:
    assert unwrap_frames(text) == commands


@pytest.mark.parametrize(
    ("text", "framed"),
    [
        ("[u0]", ("u0", "")),
        ("[u0][u1]", ("u0", "[u1]")),
        ("hello [u0,w0:6] bye", ("u0,w0:6", " bye")),
        ("[u0]junk[u1]\n", ("u0", "junk[u1]\n")),
        ("[u0[u1]", ("u0[u1", "")),  # from the first '[' to the first ']' after it
        ("u0]", None),
        ("[u0", None),
    ],
)
def test_a_request_is_its_first_frame(text: str, framed: tuple[str, str] | None) -> None:
    assert first_frame(text) == framed


CODEC = FramedCodec({"u0": "sensor", "u1": "sensor", "w0": "drive"})


@pytest.mark.parametrize(
    ("data", "commands", "dropped"),
    [
        (b"[u0]", "u0", ""),
        (b"[u0]\n", "u0", ""),  # a line ending after the frame: text outside, not a frame
        (b"hello [u1] bye", "u1", ""),
        (b"[u0][u1]", "u0", "[u1]"),
        (b"[u0,w0:6][u1]junk[w0:1]", "u0,w0:6", "[u1]junk[w0:1]"),
        (b"[u0]\n[u1", "u0", "[u1"),  # a frame begun is dropped too
    ],
)
def test_the_decoder_answers_the_first_frame_and_keeps_the_rest_for_the_log(
    data: bytes, commands: str, dropped: str
) -> None:
    decoded = CODEC.decode(data)
    assert isinstance(decoded, CommandText)
    assert (decoded.text, decoded.count, decoded.dropped) == (
        commands,
        commands.count(",") + 1,
        dropped,
    )
    assert [c.device for c in decoded.commands] == commands.replace(":6", "").split(",")


def test_what_is_dropped_is_cut_short_for_the_log() -> None:
    decoded = CODEC.decode(b"[u0]" + b"[u1]" * 10_000)
    assert isinstance(decoded, CommandText)
    assert len(decoded.dropped) == MAX_SHOWN
    assert decoded.dropped.startswith("[u1][u1]")
    assert decoded.dropped.endswith("...")
    assert CODEC.encode(decoded, [39.5]) == b"[u0:39.5]"


def test_framed_entries_as_the_original_writes_them() -> None:
    codec = FramedCodec({"u0": "sensor", "w0": "drive", "m0": "motor"}, round_digits=3)
    decoded = codec.decode(b"[u0,w0:6,w0:1,xx,zz,m0]")
    values = [15.4512, math.inf, math.nan, math.inf, math.nan, 0.0]
    assert codec.encode(decoded, values) == (
        b"[u0:15.451,w0:True,w0:False,xx:DRIVE STOP,zz:Not Found,m0:0.0]"
    )
    assert codec.decode(b"u0").count == 0  # no frame: nothing is sent back


def test_framed_values_read_back_as_the_packed_protocol_numbers() -> None:
    assert framed_value("True") == math.inf
    assert framed_value("DRIVE STOP") == math.inf
    assert math.isnan(framed_value("False"))
    assert math.isnan(framed_value("Not Found"))
    assert framed_value("15.45") == 15.45


@pytest.mark.parametrize(
    ("text", "device", "value", "rules"),
    [
        ("r0-0-45", "r0", 0.0, ("zero",)),  # the typo 'r0-0' + str(angle): a zero turn
        ("w0:3", "w0", 3.0, ()),
        ("w0 3", "w0", 3.0, ("skip",)),
        ("w0_3", "w0", 3.0, ("skip",)),
        ("w03", "w0", 0.0, ("skip", "zero")),  # a zero drive
        ("w0-abc", "w0", 0.0, ("zero",)),
        ("u0", "u0", 0.0, ()),
    ],
)
def test_lenient_parsing_is_the_originals(
    text: str, device: str, value: float, rules: tuple[str, ...]
) -> None:
    command = parse_command(text, lenient=True)
    assert (command.device, command.value, command.lenient, command.error) == (
        device,
        value,
        rules,
        None,
    )


@pytest.mark.parametrize("text", ["w0-nan", "w0-inf", "w0-1e300"])
def test_lenient_parsing_still_refuses_values_no_drive_means(text: str) -> None:
    assert parse_command(text, lenient=True).error


def test_strict_parsing_accepts_the_v12_separator_only() -> None:
    assert parse_command("w0:3").value == 3.0
    assert parse_command("w0 3").error
    assert parse_command("r0-0-45").error


# ----------------------------------------------------------------------------- two-port TCP


def test_v12_client_over_two_port_gets_exactly_the_originals_replies() -> None:
    with serving(framed_sim()) as (_, link):
        assert two_port_raw(link, b"[u0]") == b"[u0:39.5]"
        assert two_port_raw(link, b"[u0][u1]") == b"[u0:39.5]"  # the first frame only
        assert two_port_raw(link, b"[u2]") == b"[u2:53.588]"
        assert two_port_raw(link, b"hello [u1] bye") == b"[u1:3.5]"
        assert two_port_raw(link, b"[zz]") == b"[zz:Not Found]"
        assert two_port_raw(link, b"u0") == b""  # no frame: closed with nothing sent
        # before anything moves: the readings cannot depend on how fast this machine answers
        assert two_port_raw(link, b"[u0,w0:0,zz]") == b"[u0:39.5,w0:True,zz:Not Found]"
        assert two_port_raw(link, b"[w0:6]") == b"[w0:True]"
        assert two_port_raw(link, b"[w0:6]") == b"[w0:False]"  # still moving
        assert two_port_raw(link, b"[xx]") == b"[xx:DRIVE STOP]"
        assert two_port_raw(link, b"[r0:-90]") == b"[r0:True]"
        assert two_port_raw(link, b"[xx]") == b"[xx:DRIVE STOP]"


TWO_FRAMES_PROGRAM = """\
import socket
import sys
import time

def transmit(data):
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as s:
        s.connect(('127.0.0.1', int(sys.argv[1])))
        s.send(data.encode('ascii'))

def receive():
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as s2:
        s2.connect(('127.0.0.1', int(sys.argv[2])))
        return s2.recv(1024).decode('ascii')

transmit('[u0][u1]')    # two frames in one message
time.sleep(0.1)
print(receive())
transmit('[u1]')        # the simulator goes on serving
time.sleep(0.1)
print(receive())
"""


@pytest.mark.slow
def test_a_v12_program_sending_two_frames_at_once_hears_the_first_as_the_original(
    tmp_path: Path, caplog: pytest.LogCaptureFixture
) -> None:
    program = tmp_path / "two_frames.py"
    program.write_text(TWO_FRAMES_PROGRAM, encoding="utf-8")
    with caplog.at_level(logging.WARNING), serving(framed_sim()) as (_, link):
        ports = [str(link.two_port.port_rx), str(link.two_port.port_tx)]
        done = subprocess.run(
            [sys.executable, str(program), *ports],
            check=False,
            capture_output=True,
            text=True,
            timeout=60,
        )
    assert done.returncode == 0, done.stderr
    assert done.stdout.splitlines() == ["[u0:39.5]", "[u1:3.5]"]
    (warned,) = [r.getMessage() for r in caplog.records if "more than one frame" in r.getMessage()]
    assert "'[u1]' is not" in warned


def test_rounding_follows_round_digits() -> None:
    with serving(framed_sim(round_digits=1)) as (_, link):
        assert two_port_raw(link, b"[u2]") == b"[u2:53.6]"


def test_a_v12_config_py_selects_the_framed_protocol_by_itself() -> None:
    config = load_config(SIMMER_PY / "default_config.py")
    assert config.settings.protocol == "framed"
    assert config.settings.lenient_commands
    assert "v1.2" in config.origin
    with serving(Simulation(config)) as (_, link):
        reply = two_port_raw(link, b"[u0,w0:0,xx]").decode("ascii")
        entries = reply[1:-1].split(",")
        assert reply.startswith("[")
        assert reply.endswith("]")
        assert entries[1:] == ["w0:True", "xx:DRIVE STOP"]
        assert entries[0].startswith("u0:")
        assert float(entries[0][3:]) > 0


def test_the_client_library_speaks_framed_two_port() -> None:
    with (
        serving(framed_sim()) as (_, link),
        connect(port_rx=link.two_port.port_rx, port_tx=link.two_port.port_tx, framed=True) as robot,
    ):
        assert robot.send("u0,u1") == [39.5, 3.5]
        assert robot.link.last_text == "[u0:39.5,u1:3.5]"
        assert robot.drive("w0", 0) == math.inf


def test_the_console_shows_the_framed_reply_as_sent() -> None:
    lines = iter(["u0,zz", "quit"])
    shown: list[str] = []
    with (
        serving(framed_sim()) as (_, link),
        connect(port_rx=link.two_port.port_rx, port_tx=link.two_port.port_tx, framed=True) as robot,
    ):
        run_console(robot, read=lambda _prompt: next(lines), echo=shown.append, history=False)
    assert "[u0:39.5,zz:Not Found]" in shown


def test_a_packed_client_hears_why_a_framed_simulator_said_nothing() -> None:
    from simmer.errors import ConnectionFailed

    with (
        serving(framed_sim()) as (_, link),
        connect(
            scheme="two-port", port_rx=link.two_port.port_rx, port_tx=link.two_port.port_tx
        ) as robot,
        pytest.raises(ConnectionFailed, match="framed"),
    ):
        robot.send("u0")


def test_the_persistent_protocol_keeps_its_packed_frames_in_framed_mode() -> None:
    with serving(framed_sim()) as (_, link), connect(port=link.stream.port) as robot:
        assert robot.send("u0,zz")[0] == 39.5


# ----------------------------------------------------------------------------- serial port


def test_v12_program_over_the_serial_port_reads_frames_until_the_end_character() -> None:
    with serving(framed_sim(), serial=True, silence=0.0) as (_, link):
        assert link.serial is not None
        with serial.Serial(link.serial.path, 9600, timeout=5) as port:
            port.write(b"[u0]")
            assert port.read_until(b"]") == b"[u0:39.5]"
            port.write(b"[u0,u1]\n")  # the line ending is text outside a frame: ignored
            assert port.read_until(b"]") == b"[u0:39.5,u1:3.5]"
            port.write(b"noise\n[zz][xx]")  # the robot reads until ']': two messages
            assert port.read_until(b"]") == b"[zz:Not Found]"
            assert port.read_until(b"]") == b"[xx:DRIVE STOP]"
            sent = len(b"[u0]" + b"[u0,u1]\n" + b"noise\n[zz][xx]")  # counted after their replies
            port.write(b"[w0:")  # a frame split across two writes, past the silence (none)
            port.flush()
            wait_for(lambda: link.serial is not None and link.serial.received == sent + 4, "[w0:")
            port.write(b"6]")
            assert port.read_until(b"]") == b"[w0:True]"
            port.write(b"[u1]")
            assert port.read_until(b"]") == b"[u1:3.5]"  # exactly one reply each before it


def test_the_client_library_speaks_framed_serial() -> None:
    with serving(framed_sim(), serial=True) as (_, link):
        assert link.serial is not None
        with connect(serial=link.serial.path, framed=True, timeout=5) as robot:
            assert robot.send("u1,zz")[0] == 3.5
            assert robot.link.last_text == "[u1:3.5,zz:Not Found]"


# ----------------------------------------------------------------------------- v1.0 and §6.2


def test_a_v10_config_with_a_v10_client_needs_no_edit() -> None:
    config = load_config(SIMMER_PY / "lab_rover_quiet.py")
    assert config.settings.reply_bytes == 8
    assert config.origin.startswith("looks like a SimMeR v1.0 config")
    assert "8-byte doubles" in config.origin
    with serving(Simulation(config)) as (_, link):
        with socket.create_connection(("127.0.0.1", link.two_port.port_rx)) as out:
            out.sendall(b"u0,u1")
        with socket.create_connection(("127.0.0.1", link.two_port.port_tx)) as back:
            data = back.recv(1024)
        assert len(data) == 16
        assert struct.unpack("<2d", data)[1] == pytest.approx(3.5, abs=0.5)


def test_a_config_py_can_still_choose_its_reply_width(tmp_path: Path) -> None:
    text = (SIMMER_PY / "lab_rover_quiet.py").read_text() + "\nreply_bytes = 4\n"
    (tmp_path / "config.py").write_text(text)
    config = load_config(tmp_path / "config.py")
    assert config.settings.reply_bytes == 4
    assert "but it sets reply_bytes" in config.origin


def test_original_parsing_over_a_transport_warns_once_per_device(
    caplog: pytest.LogCaptureFixture,
) -> None:
    config = load_config(SIMMER_PY / "lab_rover_quiet.py")
    with caplog.at_level(logging.WARNING), serving(Simulation(config), speed=None) as (_, link):
        assert two_port_send(link, b"r0-0-45", width=8) == [math.inf]  # a zero turn
        assert two_port_send(link, b"r0-0-90", width=8) == [math.inf]
        assert two_port_send(link, b"w03", width=8) == [math.inf]  # a zero drive
        assert two_port_send(link, b"w0:3", width=8) == [math.inf]
    zero = [r for r in caplog.records if "read as 0" in r.getMessage()]
    assert [r.getMessage().split("'")[1] for r in zero] == ["r0-0-45", "w03"]
    skip = [r for r in caplog.records if "third character" in r.getMessage()]
    assert [r.getMessage().split("'")[1] for r in skip] == ["w03"]


def test_native_files_keep_strict_parsing() -> None:
    sim = Simulation(make_config(default_data()))
    assert math.isnan(sim.command("r0-0-45")[0])
    assert math.isnan(sim.command("w03")[0])
    assert sim.command("w0:3") == [math.inf]
