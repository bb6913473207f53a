"""The TCP transports over real loopback sockets: SimMeR's two-port scheme and the persistent
stream protocol, with every bad input the issue lists."""

from __future__ import annotations

import contextlib
import logging
import math
import select
import socket
import struct
import threading
from concurrent.futures import ThreadPoolExecutor

import pytest

from link_support import read_frame, serving, two_port_collect, two_port_send, unpack
from simmer.protocol import MAX_MESSAGE_BYTES
from simmer.transport import Transports

from helpers import DEADLINE, LAB_SEQUENCE, default_data, make_sim, wait_for

pytestmark = pytest.mark.timeout(60)
INF = math.inf


def partly_received(link: Transports, data: bytes) -> bool:
    """Whether a stream connection holds ``data``, the start of a message (in the loop's
    hands, not the kernel's)."""
    return any(c.inbox == data for c in list(link.stream._connections))


def is_nan(values: list[float]) -> bool:
    return all(math.isnan(v) for v in values)


def stream(link_port: int) -> socket.socket:
    sock = socket.create_connection(("127.0.0.1", link_port), timeout=10)
    sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
    return sock


def wait_idle_two_port(link: Transports, width: int) -> None:
    wait_for(lambda: math.isinf(two_port_send(link, b"w0-0", width)[0]), "the drive to end")


@pytest.mark.parametrize("width", [4, 8])
def test_original_style_client_drives_the_lab_sequence_to_the_block(width: int) -> None:
    data = default_data()
    data["reply_bytes"] = width
    with serving(make_sim(data), speed=None) as (runner, link):
        for message in LAB_SEQUENCE:
            assert two_port_send(link, message.encode(), width) == [INF]
            wait_idle_two_port(link, width)
        u0 = two_port_send(link, b"u0", width)[0]
        pose = runner.sim.robot.pose
    assert math.dist((pose.x, pose.y), (66, 12)) < 0.5
    assert u0 == pytest.approx(3.0, abs=0.2)


def test_two_port_bad_inputs_get_nan_and_the_server_keeps_serving(
    caplog: pytest.LogCaptureFixture,
) -> None:
    caplog.set_level(logging.WARNING)
    with serving() as (_, link):
        assert is_nan(two_port_send(link, b"\n"))  # empty message
        assert is_nan(two_port_send(link, b"zz"))  # unknown device
        assert is_nan(two_port_send(link, b"w0-abc"))  # non-numeric
        for value in (b"nan", b"inf", b"1e308"):
            assert is_nan(two_port_send(link, b"w0-" + value))
        assert is_nan(two_port_send(link, b"w06"))  # missing separator
        assert len(two_port_send(link, b"u0,\xff\xfe,u1")) == 3  # non-UTF-8
        assert is_nan(two_port_send(link, b"u0,\xff\xfe,u1"))
        assert two_port_send(link, b"u0,zz,u1")[1] != two_port_send(link, b"u0")[0]
        assert two_port_send(link, b"u0")[0] > 0
    assert "no device 'zz'" in caplog.text
    assert "not utf-8" in caplog.text


def test_two_port_oversize_message_gets_one_nan() -> None:
    with serving() as (_, link):
        out = socket.create_connection(("127.0.0.1", link.two_port.port_rx))
        try:
            out.sendall(b"u0," * (MAX_MESSAGE_BYTES // 3 + 10))
        except OSError:
            pass  # the server may stop reading (and reset) once it has seen too much
        finally:
            out.close()
        with socket.create_connection(("127.0.0.1", link.two_port.port_tx), timeout=10) as back:
            assert back.recv(64) == struct.pack("<f", math.nan)
        assert two_port_send(link, b"u0")[0] > 0


def test_two_port_silent_connection_is_no_message(caplog: pytest.LogCaptureFixture) -> None:
    caplog.set_level(logging.DEBUG, logger="simmer.transport")
    with serving() as (_, link):
        socket.create_connection(("127.0.0.1", link.two_port.port_rx)).close()
        wait_for(lambda: "sent nothing: no message" in caplog.text, "the silent connection")
        assert two_port_send(link, b"u0,u1")[1] == pytest.approx(3.5)


def test_two_port_reply_kept_when_reply_client_leaves_early() -> None:
    with serving(speed=None) as (_, link):
        early = socket.create_connection(("127.0.0.1", link.two_port.port_tx))
        early.close()  # leaves before any message: must not swallow the next reply
        wait_for(lambda: link.two_port.accepted == 1, "the early reply connection")
        assert two_port_send(link, b"u1") == [pytest.approx(3.5)]
        assert two_port_send(link, b"u0,u1")[1] == pytest.approx(3.5)


def test_stream_protocol_answers_many_messages_on_one_connection() -> None:
    with serving() as (_, link), stream(link.stream.port) as sock:
        sock.sendall(b"u0,u1\nw0-6\n")  # two messages in one write
        assert read_frame(sock)[1] == pytest.approx(3.5)
        assert read_frame(sock) == [INF]
        sock.sendall(b"w0")
        wait_for(lambda: partly_received(link, b"w0"), "the first half")
        sock.sendall(b"-6\r\n")  # one message over two writes
        assert is_nan(read_frame(sock))  # busy


def test_stream_bad_inputs(caplog: pytest.LogCaptureFixture) -> None:
    caplog.set_level(logging.WARNING)
    with serving() as (_, link), stream(link.stream.port) as sock:
        for bad in [b"", b"zz", b"w0-x", b"w0-nan", b"w0-inf", b"w0-1e308", b"w06", b"\xff,\xfe"]:
            sock.sendall(bad + b"\n")
            replies = read_frame(sock)
            assert is_nan(replies), bad
            assert len(replies) == bad.count(b",") + 1
        sock.sendall(b"u0\n")
        assert read_frame(sock)[0] > 0
    assert "bad message" in caplog.text


def test_stream_oversize_line_gets_nan_then_a_clean_close() -> None:
    with serving() as (_, link):
        with stream(link.stream.port) as sock:
            with contextlib.suppress(OSError):
                sock.sendall(b"u" * (MAX_MESSAGE_BYTES + 2))
            assert is_nan(read_frame(sock))
            assert sock.recv(16) == b""
        with stream(link.stream.port) as sock:
            sock.sendall(b"u0\n")
            assert read_frame(sock)[0] > 0


def test_two_clients_interleaving_each_get_their_own_replies() -> None:
    with serving() as (_, link), stream(link.stream.port) as a, stream(link.stream.port) as b:
        for _ in range(50):
            a.sendall(b"u1\n")
            b.sendall(b"u0,u1,m0\n")
            assert len(read_frame(b)) == 3
            assert read_frame(a) == [pytest.approx(3.5)]
            assert two_port_send(link, b"u1,u1") == [pytest.approx(3.5)] * 2


def still_open(sock: socket.socket) -> bool:
    """True while the server has neither closed ``sock`` nor sent it anything."""
    timeout = sock.gettimeout()
    sock.setblocking(False)
    try:
        sock.recv(1)
    except BlockingIOError:
        return True
    finally:
        sock.settimeout(timeout)
    return False


def test_idle_clients_do_not_hold_up_others() -> None:
    """Two clients connect and say nothing (the original server waited on them forever) while
    others come and go; both stay connected throughout, and are served when they speak."""
    with serving() as (_, link):
        idle_stream = stream(link.stream.port)
        idle_rx = socket.create_connection(("127.0.0.1", link.two_port.port_rx))
        wait_for(lambda: link.stream.accepted == 1, "the idle stream client")
        served = 0
        try:
            for _ in range(11):
                with stream(link.stream.port) as sock:
                    sock.sendall(b"u1\n")
                    assert read_frame(sock) == [pytest.approx(3.5)]
                assert two_port_send(link, b"u1") == [pytest.approx(3.5)]
                served += 1
            assert still_open(idle_stream)
            assert still_open(idle_rx)
            idle_stream.sendall(b"u1\n")
            assert read_frame(idle_stream) == [pytest.approx(3.5)]
            idle_rx.sendall(b"u0,u1")
            idle_rx.close()
            assert unpack(two_port_collect(link))[1] == pytest.approx(3.5)
        finally:
            idle_stream.close()
            idle_rx.close()
    assert served > 10


def test_client_disconnecting_before_reading_reply() -> None:
    with serving() as (_, link):
        for _ in range(5):
            sock = stream(link.stream.port)
            sock.sendall(b"u0,u1,u2,u3\n" * 20)
            sock.close()
        with stream(link.stream.port) as sock:
            sock.sendall(b"u1\n")
            assert read_frame(sock) == [pytest.approx(3.5)]
        assert two_port_send(link, b"u1") == [pytest.approx(3.5)]


def test_fifty_clients_at_once_each_get_their_own_reply() -> None:
    with serving() as (runner, link):
        devices = ["u0", "u1", "u2", "u3", "m0"]
        expected = {d: runner.bus.submit(d, "test").result(timeout=5)[0] for d in devices}
        barrier = threading.Barrier(50)

        def one(i: int) -> tuple[str, list[float]]:
            message = ",".join(devices[(i + k) % 5] for k in range(1 + i % 5))
            with stream(link.stream.port) as sock:
                barrier.wait()
                for _ in range(5):
                    sock.sendall(message.encode() + b"\n")
                    replies = read_frame(sock)
                    assert replies == [pytest.approx(expected[d]) for d in message.split(",")]
            return message, replies

        with ThreadPoolExecutor(50) as pool:
            results = list(pool.map(one, range(50)))
    assert len(results) == 50


def test_stream_client_that_sends_much_before_reading_gets_every_reply_in_order() -> None:
    count = 20000
    with serving() as (_, link), stream(link.stream.port) as sock:
        sender = threading.Thread(target=sock.sendall, args=(b"u1\nu0,u1\n" * (count // 2),))
        sender.start()  # replies pile up while the client is still writing: back-pressure
        assert select.select([sock], [], [], DEADLINE)[0] == [sock]  # the first has come
        replies = [read_frame(sock) for _ in range(count)]
        sender.join()
    assert [len(r) for r in replies[:4]] == [1, 2, 1, 2]
    assert all(r[-1] == pytest.approx(3.5) for r in replies)
