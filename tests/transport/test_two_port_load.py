"""SimMeR's two-port scheme under load: a reply connection is answered only once everything
already queued at the send port is taken, so a sequential client gets its own reply every
time, beside flooding clients or busy processes, and never falls one reply behind; replies
nobody collects are logged within a budget."""

from __future__ import annotations

import logging
import re
import socket
import struct
import subprocess
import sys
import textwrap
from collections.abc import Callable, Iterator
from contextlib import contextmanager

import pytest

from link_support import serving, two_port_collect, two_port_send, unpack
from simmer.transport import Transports
from simmer.transport.tcp import LOGGED_LINES

from helpers import wait_for

pytestmark = pytest.mark.timeout(300)

FLOODERS = 16
MESSAGES = ["u1", "u0,u1"]
"""Alternated: each reply's length says whose it is (one value, then two)."""
UNCOLLECTED = 1000

FLOOD = textwrap.dedent(
    """
    import select, socket, sys
    port, count = int(sys.argv[1]), int(sys.argv[2])
    LINES = 64
    batch = b"u0,u1,u2,u3\\n" * LINES
    frame = 3 + 4 * 4
    socks = [socket.create_connection(("127.0.0.1", port)) for _ in range(count)]
    print("flooding", flush=True)
    while not select.select([sys.stdin], [], [], 0)[0]:
        for sock in socks:
            sock.sendall(batch)
        for sock in socks:
            left = frame * LINES
            while left:
                left -= len(sock.recv(left))
    """
)
"""16 persistent-protocol clients in one process, each sending 64 lines at a time and
reading the 64 replies, until the test closes its stdin."""


@contextmanager
def flooding(link: Transports) -> Iterator[None]:
    """:data:`FLOODERS` clients flooding the persistent port while the block runs."""
    flood = subprocess.Popen(
        [sys.executable, "-c", FLOOD, str(link.stream.port), str(FLOODERS)],
        stdin=subprocess.PIPE,
        stdout=subprocess.PIPE,
        text=True,
    )
    assert flood.stdin is not None
    assert flood.stdout is not None
    try:
        assert flood.stdout.readline() == "flooding\n"
        wait_for(lambda: link.stream.accepted >= FLOODERS, "the flooding clients")
        yield
    finally:
        flood.stdin.close()
        try:
            flood.wait(timeout=30)
        finally:
            flood.kill()
            flood.stdout.close()


def send_close_read(link: Transports, message: str) -> list[float]:
    """The original clients' way: send on port_rx and close, then read port_tx."""
    return two_port_send(link, message.encode())


def send_read_close(link: Transports, message: str) -> list[float]:
    """Send on port_rx and read the reply from port_tx before closing the send connection."""
    with socket.create_connection(("127.0.0.1", link.two_port.port_rx)) as out:
        out.sendall(message.encode())
        return unpack(two_port_collect(link))


def send_open_close_read(link: Transports, message: str) -> list[float]:
    """Send on port_rx, open the reply connection, then close the send connection and read."""
    out = socket.create_connection(("127.0.0.1", link.two_port.port_rx))
    with out:
        out.sendall(message.encode())
        back = socket.create_connection(("127.0.0.1", link.two_port.port_tx), timeout=10)
    with back:
        data = b""
        while chunk := back.recv(1024):
            data += chunk
    return unpack(data)


Exchange = Callable[[Transports, str], list[float]]


def lengths(link: Transports, count: int, exchange: Exchange = send_close_read) -> list[int]:
    """How many values each of ``count`` alternated messages got back; a client gets its own
    replies when this alternates 1, 2, 1, 2..."""
    return [len(exchange(link, MESSAGES[index % 2])) for index in range(count)]


def own(count: int) -> list[int]:
    """What :func:`lengths` gives when every reply is the client's own."""
    return [index % 2 + 1 for index in range(count)]


@pytest.mark.slow
def test_a_sequential_client_beside_16_flooders_gets_only_its_own_replies() -> None:
    with serving() as (_, link):
        with flooding(link):
            during = lengths(link, 150)
        after = lengths(link, 50)
    shifted = sum(got != want for got, want in zip(during, own(150), strict=True))
    assert shifted == 0, f"{shifted} of 150 replies were not the client's own"
    assert after == own(50), "still behind after the flood stopped"


@pytest.mark.slow
@pytest.mark.usefixtures("busy_cpu")
@pytest.mark.parametrize("exchange", [send_close_read, send_read_close, send_open_close_read])
def test_every_reply_comes_beside_busy_processes(exchange: Exchange) -> None:
    with serving() as (_, link):
        assert lengths(link, 500, exchange) == own(500)


def log_lines(caplog: pytest.LogCaptureFixture) -> list[str]:
    """What the two-port server has logged so far."""
    return [r.getMessage() for r in caplog.records if r.name == "simmer.transport"]


@pytest.mark.slow
def test_replies_nobody_collects_are_logged_within_a_budget(
    caplog: pytest.LogCaptureFixture,
) -> None:
    """Each dropped reply is a line, or counted in one, and at most LOGGED_LINES lines come
    between counts (30,000 messages nobody collected wrote 29,999 lines)."""
    caplog.set_level(logging.INFO, logger="simmer.transport")

    def said() -> list[str]:
        return [line for line in log_lines(caplog) if "is dropped" in line]

    def counts() -> list[int]:
        found = (re.search(r"(\d+) more line", line) for line in log_lines(caplog))
        return [int(match[1]) for match in found if match]

    with serving() as (_, link):
        for _ in range(UNCOLLECTED):
            with socket.create_connection(("127.0.0.1", link.two_port.port_rx)) as out:
                out.sendall(b"u1")
        # Collected once all are answered: the first reply (v1.1 kept only the first).
        assert two_port_collect(link) == struct.pack("<f", 3.5)
        wait_for(
            lambda: len(said()) + sum(counts()) == UNCOLLECTED - 1, "every drop to be accounted"
        )
    assert len(said()) <= LOGGED_LINES * (len(counts()) + 1)
