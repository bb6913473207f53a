"""The virtual serial port: a real pseudo-terminal driven with pyserial, as a robot program
would drive the Arduino's Bluetooth port."""

from __future__ import annotations

import math
import struct
import time
from pathlib import Path

import pytest
import serial

from link_support import serving

pytestmark = pytest.mark.timeout(60)


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


def test_one_command_split_across_two_writes_20_ms_apart() -> None:
    with serving(serial=True) as (_, link):
        assert link.serial is not None
        with serial.Serial(link.serial.path, 9600, timeout=5) as port:
            port.write(b"u")
            port.flush()
            time.sleep(0.02)
            port.write(b"1\n")
            assert floats(port.read(4)) == [pytest.approx(3.5)]
            port.timeout = 0.2
            assert port.read(4) == b""  # exactly one reply


def test_two_commands_60_ms_apart_without_newlines() -> None:
    with serving(serial=True) as (_, link):
        assert link.serial is not None
        with serial.Serial(link.serial.path, 9600, timeout=5) as port:
            port.write(b"u1")
            port.flush()
            time.sleep(0.06)
            port.write(b"w0-1")
            assert floats(port.read(8)) == [pytest.approx(3.5), math.inf]


def test_non_utf8_and_oversize_get_nan_and_serving_continues() -> None:
    with serving(serial=True) as (_, link):
        assert link.serial is not None
        with serial.Serial(link.serial.path, 9600, timeout=5) as port:
            port.write(b"\xff\xfe,u0\n")
            assert all(math.isnan(v) for v in floats(port.read(8)))
            port.write(b"u" * (64 * 1024 + 10))
            port.write(b"\n")
            assert math.isnan(floats(port.read(4))[0])
            port.reset_input_buffer()
            time.sleep(0.1)
            port.reset_input_buffer()
            port.write(b"u1\n")
            assert floats(port.read(4)) == [pytest.approx(3.5)]
