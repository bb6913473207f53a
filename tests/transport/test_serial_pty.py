"""The virtual serial port: a real pseudo-terminal driven with pyserial, as a robot program
would drive the Arduino's Bluetooth port; a message that fails keeps the port, and the link
path never replaces what SimMeR did not create."""

from __future__ import annotations

import logging
import math
import os
import struct
from pathlib import Path

import pytest
import serial

from link_support import LONG_SILENCE, loop, serving
from simmer.errors import SimmerError
from simmer.protocol import Decoded, PackedCodec
from simmer.runner import Runner
from simmer.transport import CommandBus, SerialServer
from simmer.world import Simulation

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


class _FlakyCodec(PackedCodec):
    """Packed replies, except that decoding ``boom`` raises (a codec bug)."""

    def decode(self, data: bytes) -> Decoded:
        if data == b"boom":
            raise RuntimeError("codec bug")
        return super().decode(data)


def test_an_exception_answering_one_serial_message_keeps_the_port(
    caplog: pytest.LogCaptureFixture,
) -> None:
    caplog.set_level(logging.ERROR)
    runner = Runner(Simulation.from_config(), speed=None)
    port = SerialServer(runner.bus, codec=_FlakyCodec())
    with port, loop(runner), serial.Serial(port.path, 9600, timeout=10) as tty:
        for _ in range(3):
            tty.write(b"boom\n")
        tty.write(b"u1\n")
        assert struct.unpack("<f", tty.read(4)) == (pytest.approx(3.5),)
    logged = [r for r in caplog.records if "codec bug" in r.getMessage()]
    assert len(logged) == 1  # the first failure in full, the rest counted
    assert "3 messages could not be answered" in caplog.text


@pytest.mark.parametrize("kind", ["symlink", "dangling", "file"])
def test_serial_link_never_replaces_what_it_did_not_create(tmp_path: Path, kind: str) -> None:
    target = tmp_path / "my-robot"
    target.write_text("mine")
    path = tmp_path / "robot"
    if kind == "symlink":
        path.symlink_to(target)
    elif kind == "dangling":
        path.symlink_to(tmp_path / "gone")
    else:
        path.write_text("a file")
    before = os.readlink(path) if path.is_symlink() else path.read_text()
    with pytest.raises(SimmerError, match="already there"):
        SerialServer(CommandBus(), path)
    after = os.readlink(path) if path.is_symlink() else path.read_text()
    assert after == before


def test_serial_link_replaced_meanwhile_is_left_alone(tmp_path: Path) -> None:
    path = tmp_path / "robot"
    port = SerialServer(CommandBus(), path)
    with port:
        path.unlink()
        path.symlink_to(tmp_path / "someone-elses")
    assert os.readlink(path) == str(tmp_path / "someone-elses")
