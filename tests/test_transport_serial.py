"""The virtual serial port: a real pseudo-terminal driven with pyserial, as a robot program
would drive the Arduino's Bluetooth port."""

from __future__ import annotations

import math
import struct
from pathlib import Path

import pytest
import serial

from link_support import LONG_SILENCE, serving

from helpers import wait_for

pytestmark = pytest.mark.timeout(60)
U0 = 39.5
"""The built-in simulation's ``u0`` reading at the start."""


def floats(data: bytes) -> list[float]:
    return [value for (value,) in struct.iter_unpack("<f", data)]


def test_newline_ends_a_command_and_replies_are_packed_floats(tmp_path: Path) -> None:
    link_path = tmp_path / "robot"
    with serving(serial=True, serial_link=link_path) as (runner, link):
        assert link.serial is not None
        assert link_path.resolve() == Path(link.serial.path).resolve()
        assert f"serial {link.serial.path}" in runner.clients
        with serial.Serial(str(link_path), 9600, timeout=5) as port:
            port.write(b"u0,u1\n")
            assert floats(port.read(8))[1] == pytest.approx(3.5)
            port.write(b"zz\n")
            assert math.isnan(floats(port.read(4))[0])
    assert not link_path.exists()


def test_one_command_split_across_two_writes_a_pause_apart() -> None:
    """The server has read the first half before the second comes, in a pause far shorter
    than the silence that would end the command."""
    with serving(serial=True, silence=LONG_SILENCE) as (_, link):
        assert link.serial is not None
        with serial.Serial(link.serial.path, 9600, timeout=5) as port:
            port.write(b"u")
            port.flush()
            wait_for(lambda: link.serial is not None and link.serial.received == 1, "'u'")
            port.write(b"1\n")
            assert floats(port.read(4)) == [pytest.approx(3.5)]
            port.write(b"u0\n")
            assert floats(port.read(4)) == [pytest.approx(U0)]  # exactly one reply before


def test_two_commands_a_silence_apart_without_newlines() -> None:
    with serving(serial=True) as (_, link):
        assert link.serial is not None
        with serial.Serial(link.serial.path, 9600, timeout=5) as port:
            port.write(b"u1")
            first = port.read(4)  # the Arduino's 50 ms of silence ended the command
            port.write(b"w0-1")
            assert floats(first + port.read(4)) == [pytest.approx(3.5), math.inf]


def test_non_utf8_and_oversize_get_nan_and_serving_continues() -> None:
    with serving(serial=True) as (_, link):
        assert link.serial is not None
        with serial.Serial(link.serial.path, 9600, timeout=5) as port:
            port.write(b"\xff\xfe,u0\n")
            assert all(math.isnan(v) for v in floats(port.read(8)))
            port.write(b"u" * (64 * 1024 + 10))
            port.write(b"\n")
            assert math.isnan(floats(port.read(4))[0])
            port.write(b"u1\n")  # after the oversize's replies (how many: how it was read)
            replies = floats(port.read(4))
            while math.isnan(replies[-1]):
                replies += floats(port.read(4))
            assert replies[-1] == pytest.approx(3.5)
