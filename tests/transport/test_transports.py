"""Every transport together: a message over the command limit gets one NaN on each."""

from __future__ import annotations

import logging
import math
import struct

import pytest
import serial

from link_support import read_frame, serving, stream, two_port_send
from simmer.protocol import MAX_COMMANDS

pytestmark = pytest.mark.timeout(60)


def test_a_message_over_the_command_limit_gets_one_nan_on_every_transport(
    caplog: pytest.LogCaptureFixture,
) -> None:
    caplog.set_level(logging.WARNING)
    over = b",".join([b"w0-1"] * (MAX_COMMANDS + 1))
    at = b",".join([b"u1"] * MAX_COMMANDS)
    with serving(serial=True) as (runner, link):
        assert link.serial is not None
        with stream(link.stream.port) as sock:
            sock.sendall(at + b"\n")
            assert read_frame(sock) == [pytest.approx(3.5)] * MAX_COMMANDS
            sock.sendall(over + b"\n")
            assert len(nan := read_frame(sock)) == 1
            assert math.isnan(nan[0])
        replies = two_port_send(link, over)
        assert len(replies) == 1
        assert math.isnan(replies[0])
        with serial.Serial(link.serial.path, 9600, timeout=10) as tty:
            tty.write(over + b"\n")
            assert math.isnan(struct.unpack("<f", tty.read(4))[0])
            tty.write(b"u1\n")
            assert struct.unpack("<f", tty.read(4)) == (pytest.approx(3.5),)
        assert not runner.sim.robot.any_drive_moving  # nothing in an over-limit message ran
    assert caplog.text.count(f"over the limit of {MAX_COMMANDS}") == 3
