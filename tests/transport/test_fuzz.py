"""Fuzzing every transport with a seeded generator: valid and malformed messages (random bytes,
runs of commas, huge and non-finite values, other scripts' digits, empty, over the limits),
each answered with exactly one reply per command (one NaN for a message over a limit), and the
simulator serving a good client afterwards. Bounded: a few hundred messages per transport."""

from __future__ import annotations

import contextlib
import math
import random
import socket
import struct

import pytest
import serial

from link_support import LONG_SILENCE, read_frame, serving
from simmer.protocol import EXPLAIN, MAX_COMMANDS, MAX_MESSAGE_BYTES
from simmer.transport import Transports

pytestmark = pytest.mark.timeout(120)
SEED = 20240901
MESSAGES = 1000

READS = ["u0", "u1", "u2", "u3", "m0", "m1", "w0-0", "r0-0", "w0:0", "xx", "w0", " u1 "]
"""Commands that never move the robot, so a reading afterwards is known."""
REFUSED_VALUES = [
    "1e308",
    "nan",
    "inf",
    "-1e10",
    "1e9999",
    "٥",
    "６",
    "0x10",
    "1_0",
    "",
    "-",
    "+-1",
]
"""Values every drive refuses (out of range or not a number): the robot stays put."""


def command(rng: random.Random) -> str:
    """One command, valid or not."""
    pick = rng.random()
    if pick < 0.5:
        return rng.choice(READS)
    if pick < 0.75:
        return rng.choice(["w0-", "r0-", "w0:", "u0-", "zz-", "m0-"]) + rng.choice(REFUSED_VALUES)
    alphabet = "uwrmx0123-:.,e+ \t\r[]?é٥６\u202e\x1b"
    return "".join(rng.choice(alphabet) for _ in range(rng.randrange(0, 6)))


def message(rng: random.Random, *, line: bool, most: int) -> bytes:
    """One message of at most ``most`` bytes; with ``line``, no ``\\n`` (it ends a line) and
    not the persistent protocol's ``?``."""
    pick = rng.random()
    if pick < 0.45:
        data = ",".join(command(rng) for _ in range(rng.randrange(1, 8))).encode()
    elif pick < 0.6:
        data = bytes(rng.randrange(256) for _ in range(rng.randrange(0, 40)))
    elif pick < 0.7:
        data = b"," * rng.choice([0, 1, 2, MAX_COMMANDS - 1, MAX_COMMANDS, MAX_COMMANDS + 1])
    elif pick < 0.8:
        data = "".join(chr(rng.randrange(32, 0x3000)) for _ in range(rng.randrange(1, 20))).encode()
    elif pick < 0.9:
        data = b",".join([b"u1"] * rng.choice([MAX_COMMANDS, MAX_COMMANDS + 1, 2 * MAX_COMMANDS]))
    else:
        data = b"u1," * rng.choice([10, (MAX_MESSAGE_BYTES + 64) // 3])
    data = data[:most]
    if line:
        data = data.replace(b"\n", b"n")
        if data.rstrip(b"\r") == EXPLAIN:
            data = b"?!"
    return data


def replies_expected(data: bytes) -> int:
    """One reply per command; one NaN for a message over a limit."""
    commands = data.count(b",") + 1
    return 1 if len(data) > MAX_MESSAGE_BYTES or commands > MAX_COMMANDS else commands


def over_limit(data: bytes) -> bool:
    return len(data) > MAX_MESSAGE_BYTES or data.count(b",") + 1 > MAX_COMMANDS


def floats(data: bytes) -> list[float]:
    return [value for (value,) in struct.iter_unpack("<f", data)]


def good_client_served(link: Transports) -> None:
    with socket.create_connection(("127.0.0.1", link.stream.port), timeout=10) as sock:
        sock.sendall(b"u1\n")
        assert read_frame(sock) == [pytest.approx(3.5)]


@pytest.mark.slow
def test_fuzz_persistent_protocol() -> None:
    rng = random.Random(SEED)
    with serving(speed=None) as (_, link):
        sock = socket.create_connection(("127.0.0.1", link.stream.port), timeout=10)
        try:
            for _ in range(MESSAGES):
                data = message(rng, line=True, most=MAX_MESSAGE_BYTES + 100)
                with contextlib.suppress(ConnectionResetError):
                    sock.sendall(data + b"\n")
                replies = read_frame(sock)
                assert len(replies) == replies_expected(data), data[:80]
                if over_limit(data):  # one NaN, then the server closes: start again
                    assert math.isnan(replies[0])
                    sock.close()
                    sock = socket.create_connection(("127.0.0.1", link.stream.port), timeout=10)
        finally:
            sock.close()
        good_client_served(link)


@pytest.mark.slow
def test_fuzz_two_port_scheme() -> None:
    rng = random.Random(SEED + 1)
    with serving(speed=None) as (_, link):
        for _ in range(MESSAGES):
            data = message(rng, line=False, most=MAX_MESSAGE_BYTES + 100) or b","
            with (
                socket.create_connection(("127.0.0.1", link.two_port.port_rx)) as out,
                contextlib.suppress(ConnectionResetError, BrokenPipeError),
            ):
                out.sendall(data)  # over 64 KiB: the server may stop reading and reset
            reply = b""
            with socket.create_connection(("127.0.0.1", link.two_port.port_tx), timeout=10) as back:
                while chunk := back.recv(65536):
                    reply += chunk
            assert len(floats(reply)) == replies_expected(data), data[:80]
            assert len(reply) % 4 == 0
        with socket.create_connection(("127.0.0.1", link.two_port.port_rx)) as out:
            out.sendall(b"u1")
        with socket.create_connection(("127.0.0.1", link.two_port.port_tx), timeout=10) as back:
            assert floats(back.recv(64)) == [pytest.approx(3.5)]
        good_client_served(link)


@pytest.mark.slow
def test_fuzz_serial_port() -> None:
    rng = random.Random(SEED + 2)
    with serving(speed=None, serial=True, silence=LONG_SILENCE) as (_, link):
        assert link.serial is not None
        with serial.Serial(link.serial.path, 9600, timeout=10) as port:
            for _ in range(MESSAGES):
                # A message the port reads as one: no newline inside, and no pause in it
                # however the pseudo-terminal hands it over (the silence is long).
                data = message(rng, line=True, most=4096)
                port.write(data + b"\n")
                expected = replies_expected(data)
                reply = port.read(4 * expected)
                assert len(reply) == 4 * expected, data[:80]
            port.write(b"u1,u1,u1\n")
            assert floats(port.read(12)) == [pytest.approx(3.5)] * 3  # nothing extra before
        good_client_served(link)
