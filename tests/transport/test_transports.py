"""Every transport together: a message over the command limit gets one NaN on each, and so
does a reading too large for a 4-byte reply."""

from __future__ import annotations

import logging
import math
import socket
import struct

import pytest
import serial

from link_support import read_frame, serving, stream, two_port_send
from simmer.options import RunOptions
from simmer.ports import FREE, STREAM_PORT, Ports
from simmer.protocol import MAX_COMMANDS
from simmer.transport import Transports
from simmer.transport.bus import CommandBus

from helpers import default_data, make_sim

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


@pytest.mark.parametrize("width", [4, 8])
def test_a_reading_too_large_for_a_4_byte_reply_is_nan_with_its_reason_on_every_transport(
    width: int, caplog: pytest.LogCaptureFixture
) -> None:
    """A device class returning 1e300 once closed the connection with an internal error."""
    caplog.set_level(logging.WARNING)
    data = default_data()
    data["reply_bytes"] = width
    sim = make_sim(data)
    sim.robot.devices["u0"].simulate = lambda value, sim: 1e300  # type: ignore[method-assign]
    with serving(sim, serial=True) as (_, link):
        assert link.serial is not None
        with stream(link.stream.port) as sock:
            sock.sendall(b"u0,u1\n")
            replies = [read_frame(sock), two_port_send(link, b"u0,u1", width)]
        with serial.Serial(link.serial.path, 9600, timeout=10) as tty:
            tty.write(b"u0,u1\n")
            replies.append(
                list(struct.unpack(f"<2{'f' if width == 4 else 'd'}", tty.read(2 * width)))
            )
    for reading, u1 in replies:
        assert u1 == pytest.approx(3.5)  # the message is answered, the connection kept
        assert math.isnan(reading) if width == 4 else reading == 1e300
    assert caplog.text.count("beyond what a 4-byte reply holds") == (3 if width == 4 else 0)


def test_options_naming_no_port_listen_on_the_configurations() -> None:
    """Ports live in one place: a run's options say only where it departs from the
    configuration (a free persistent port here), and the two-port pair is the file's."""
    with socket.create_server(("127.0.0.1", 0)) as a, socket.create_server(("127.0.0.1", 0)) as b:
        rx, tx = a.getsockname()[1], b.getsockname()[1]
    data = default_data()
    data.update(port_rx=rx, port_tx=tx, host="127.0.0.1")
    sim = make_sim(data)
    bus = CommandBus()
    link = Transports(bus, sim.config, RunOptions(ports=Ports(stream=FREE)))
    try:
        assert (link.host, link.two_port.port_rx, link.two_port.port_tx) == ("127.0.0.1", rx, tx)
        assert link.stream.port not in (0, STREAM_PORT)
    finally:
        link.close()
        bus.close()
