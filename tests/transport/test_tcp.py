"""The TCP transports over real loopback sockets: SimMeR's two-port scheme and the persistent
stream protocol, with every bad input the issue lists, and what keeps one client from stopping
or starving the others (a failing connection, huge lines, replies nobody collects, running out
of descriptors, clients that never read or never finish a line, idle clients); ``?`` says why
a reply was NaN."""

from __future__ import annotations

import contextlib
import logging
import math
import re
import select
import selectors
import socket
import struct
import threading
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import pytest

from link_support import (
    closed_by_server,
    launch,
    loop,
    output,
    read_frame,
    read_text_frame,
    serving,
    stop,
    stream,
    stream_port_of,
    two_port_collect,
    two_port_send,
    unpack,
)
from simmer.client import connect
from simmer.protocol import FRAME_HEADER, MAX_MESSAGE_BYTES
from simmer.runner import Runner
from simmer.transport import CommandBus, StreamServer, Transports
from simmer.transport.tcp import ACCEPT_BACKOFF, MAX_IN_FLIGHT, MAX_UNCLAIMED, RECV_SIZE
from simmer.world import Simulation

from helpers import DEADLINE, LAB_SEQUENCE, default_data, let_time_pass, make_sim, wait_for

pytestmark = pytest.mark.timeout(60)
INF = math.inf


def partly_received(link: Transports, data: bytes) -> bool:
    """Whether a stream connection holds ``data``, the start of a message (in the loop's
    hands, not the kernel's)."""
    return any(c.inbox == data for c in list(link.stream._connections))


def is_nan(values: list[float]) -> bool:
    return all(math.isnan(v) for v in values)


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


@pytest.mark.slow
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


def quick_sim(timeout: float = 300.0, idle_timeout: float = 3600.0) -> Simulation:
    data = default_data()
    data["timeout"] = timeout
    data["idle_timeout"] = idle_timeout
    return make_sim(data)


def test_an_exception_serving_one_connection_closes_it_and_the_loop_serves_on(
    caplog: pytest.LogCaptureFixture,
) -> None:
    caplog.set_level(logging.ERROR, logger="simmer.transport")
    runner = Runner(Simulation.from_config(), speed=None)
    broken = StreamServer(runner.bus, port=0, encoding="rot13")  # as `simmer check` once let by
    good = StreamServer(runner.bus, port=0)
    with broken, good, loop(runner):
        for _ in range(2):  # the second failure shows the first one left the loop running
            with stream(broken.port) as sock:
                sock.sendall(b"u1\n")
                assert closed_by_server(sock)
        with stream(good.port) as sock:
            sock.sendall(b"u1\n")
            assert read_frame(sock) == [pytest.approx(3.5)]
    failures = [r for r in caplog.records if "internal error" in r.getMessage()]
    assert len(failures) == 2  # once per connection, naming the client
    assert all("stream 127.0.0.1:" in r.getMessage() for r in failures)


def test_a_line_of_65536_commands_gets_one_nan_and_a_close() -> None:
    with serving() as (_, link):
        with stream(link.stream.port) as sock:
            sock.sendall(b"," * 65535 + b"\n")  # 65,536 empty commands in under 64 KiB
            replies = read_frame(sock)
            assert len(replies) == 1
            assert math.isnan(replies[0])
            assert closed_by_server(sock)
        with stream(link.stream.port) as sock:
            sock.sendall(b"u1\n")
            assert read_frame(sock) == [pytest.approx(3.5)]


def test_a_reply_connection_with_nothing_to_collect_is_closed_at_once() -> None:
    # As the originals did (BEHAVIOUR §6.4): an empty transmit buffer closes the connection
    # with nothing sent. It then cannot take the next client's reply either.
    with serving() as (_, link):
        with socket.create_connection(("127.0.0.1", link.two_port.port_tx), timeout=10) as idle:
            assert idle.recv(64) == b""
        assert two_port_send(link, b"u1") == [pytest.approx(3.5)]
        assert two_port_send(link, b"u0,u1")[1] == pytest.approx(3.5)


def test_a_persistent_connection_idle_between_messages_is_closed_after_idle_timeout(
    caplog: pytest.LogCaptureFixture,
) -> None:
    caplog.set_level(logging.INFO, logger="simmer.transport")
    with serving(quick_sim(idle_timeout=0.05)) as (_, link), stream(link.stream.port) as sock:
        for _ in range(3):  # a reply and a new message reset the clock each time
            sock.sendall(b"u1\n")
            assert read_frame(sock) == [pytest.approx(3.5)]
        assert closed_by_server(sock)
        with connect(port=link.stream.port) as robot:  # the server goes on serving
            assert robot.read("u1") == pytest.approx(3.5)
    assert "0.05 s between messages (idle_timeout)" in caplog.text


@pytest.mark.slow
def test_unclaimed_replies_expire(caplog: pytest.LogCaptureFixture) -> None:
    caplog.set_level(logging.INFO, logger="simmer.transport")
    with serving(quick_sim(timeout=1.0)) as (_, link):
        with socket.create_connection(("127.0.0.1", link.two_port.port_rx)) as killed:
            killed.sendall(b"u1")  # a client that sent and never came for its reply
        wait_for(lambda: len(link.two_port.pending) == 1, "the message")
        wait_for(lambda: not link.two_port.pending, "the reply to expire")
        u0 = two_port_send(link, b"u0")
        assert u0 != [pytest.approx(3.5)]  # its own reply, not the expired one
    assert "dropped 1 reply nobody collected" in caplog.text


def test_packed_replies_nobody_collects_keep_only_the_first_as_v1_1_did(
    caplog: pytest.LogCaptureFixture,
) -> None:
    # SimMeR v1.0/v1.1's set_buffer_tx fills the transmit buffer only while it is empty.
    caplog.set_level(logging.INFO, logger="simmer.transport")
    with serving() as (_, link):
        for message in (b"u1", b"u0", b"u3"):
            with socket.create_connection(("127.0.0.1", link.two_port.port_rx)) as out:
                out.sendall(message)
        wait_for(lambda: caplog.text.count("is dropped: an earlier reply") == 2, "the drops")
        assert [p.decoded.text for p in link.two_port.pending] == ["u1"]
        with socket.create_connection(("127.0.0.1", link.two_port.port_tx), timeout=10) as back:
            assert back.recv(64) == struct.pack("<f", 3.5)
            assert back.recv(64) == b""


@pytest.mark.slow
def test_framed_replies_nobody_collects_are_bounded(caplog: pytest.LogCaptureFixture) -> None:
    caplog.set_level(logging.WARNING, logger="simmer.transport")
    framed = make_sim(default_data() | {"protocol": "framed", "str_encoding": "ascii"})
    with serving(framed) as (_, link):
        for _ in range(MAX_UNCLAIMED + 44):
            with socket.create_connection(("127.0.0.1", link.two_port.port_rx)) as out:
                out.sendall(b"[u0]")
        with socket.create_connection(("127.0.0.1", link.two_port.port_rx)) as out:
            out.sendall(b"[u3]")
        pending = link.two_port.pending
        wait_for(lambda: bool(pending) and pending[-1].decoded.text == "u3", "the last message")
        assert len(pending) == MAX_UNCLAIMED
        wait_for(lambda: dropped(caplog) == 45, "the log lines")  # one line per sweep at most


def dropped(caplog: pytest.LogCaptureFixture) -> int:
    """How many dropped replies the log has reported."""
    found = (re.search(r"dropped (\d+) repl", r.getMessage()) for r in caplog.records)
    return sum(int(match[1]) for match in found if match)


@pytest.mark.slow
def test_out_of_descriptors_backs_off_logs_once_and_recovers(tmp_path: Path) -> None:
    proc = launch(tmp_path, nofile=48)
    try:
        port = stream_port_of(tmp_path)
        with stream(port) as early:
            flood = [socket.create_connection(("127.0.0.1", port)) for _ in range(60)]
            try:
                wait_for(lambda: "accept" in output(tmp_path, "err"), "the descriptors to run out")
                for _ in range(30):  # a connection already open is served meanwhile
                    early.sendall(b"u1\n")
                    assert read_frame(early) == [pytest.approx(3.5)]
                    let_time_pass(ACCEPT_BACKOFF / 10)  # 30 of them: three back-off periods
            finally:
                for sock in flood:
                    sock.close()
            wait_for(lambda: "accepting connections again" in output(tmp_path, "err"), "recovery")
        with stream(port) as late:
            late.sendall(b"u1\n")
            assert read_frame(late) == [pytest.approx(3.5)]
        assert stop(proc) == 0
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
    log = output(tmp_path, "err")
    assert log.count("cannot accept") == 1, log[:2000]
    assert "accept failed" not in log


@pytest.mark.slow
def test_connections_that_never_send_a_complete_message_are_closed() -> None:
    with serving(quick_sim(timeout=1.0)) as (_, link):
        silent = stream(link.stream.port)
        partial = stream(link.stream.port)
        talker = stream(link.stream.port)
        rx = socket.create_connection(("127.0.0.1", link.two_port.port_rx), timeout=10)
        try:
            talker.sendall(b"u1\n")
            assert read_frame(talker) == [pytest.approx(3.5)]
            partial.sendall(b"u1")  # the rest never comes
            rx.sendall(b"u1")  # never closed: never a whole message
            for sock in (silent, partial, rx):
                assert closed_by_server(sock)
            talker.sendall(b"u1\n")  # idle between messages is not idle: still served
            assert read_frame(talker) == [pytest.approx(3.5)]
        finally:
            for sock in (silent, partial, talker, rx):
                sock.close()


def test_a_client_that_never_reads_delays_nobody_and_holds_a_bounded_amount() -> None:
    with serving(speed=None) as (runner, link):
        hog = socket.socket()
        hog.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 4096)  # fills at once: never read
        hog.connect(("127.0.0.1", link.stream.port))
        wait_for(lambda: len(link.stream._connections) == 1, "the hog's connection")
        (hogging,) = link.stream._connections
        hogging.conn.setsockopt(socket.SOL_SOCKET, socket.SO_SNDBUF, 4096)  # a slow network
        stop = threading.Event()
        sender = threading.Thread(target=_send_until, args=(hog, stop))
        sampler = threading.Thread(target=_sample, args=(runner.bus, stop, most := [0]))
        sender.start()
        sampler.start()
        try:
            wait_for(
                lambda: hogging.events == selectors.EVENT_WRITE, "the hog's replies to back up"
            )
            with stream(link.stream.port) as polite:
                for _ in range(100):
                    polite.sendall(b"u1\n")
                    assert read_frame(polite) == [pytest.approx(3.5)]
            assert hogging.in_flight <= MAX_IN_FLIGHT
            assert len(hogging.inbox) <= MAX_MESSAGE_BYTES + RECV_SIZE
            assert len(hogging.outbox) <= 64 * 1024
        finally:
            stop.set()
            hog.shutdown(socket.SHUT_RDWR)
            sender.join()
            sampler.join()
            hog.close()
    assert most[0] <= MAX_IN_FLIGHT + 1  # requests waiting for the loop, all clients together


def _send_until(sock: socket.socket, stop: threading.Event) -> None:
    """Send messages (4 commands each) until stopped or the socket fails; never read."""
    chunk = b"u0,u1,u2,u3\n" * 10_000
    with contextlib.suppress(OSError):
        while not stop.is_set():
            sock.sendall(chunk)


def _sample(bus: CommandBus, stop: threading.Event, most: list[int]) -> None:
    """Record the most requests ever seen waiting on ``bus``."""
    while not stop.wait(0.0005):  # a sample every half millisecond until stopped
        most[0] = max(most[0], bus.queued)


def test_explain_gives_the_reasons_of_the_last_message() -> None:
    with serving() as (_, link), connect(port=link.stream.port, timeout=10) as robot:
        replies = robot.send("u1,zz,w0-x")
        assert replies[0] == pytest.approx(3.5)
        assert all(math.isnan(v) for v in replies[1:])
        why = robot.explain()
        assert why is not None
        lines = why.splitlines()
        assert len(lines) == 2
        assert "no device 'zz' on the robot" in lines[0]
        assert "'x' is not a decimal number" in lines[1]
        assert robot.send("w0-6") == [math.inf]
        assert math.isnan(robot.send("r0-90")[0])
        assert "a drive is still moving" in (robot.explain() or "")
        robot.send("u1")
        assert robot.explain() == ""


def test_explain_is_answered_in_order_with_pipelined_messages() -> None:
    with serving() as (_, link), stream(link.stream.port) as sock:
        sock.sendall(b"zz\n?\nu1\n?\n\xff\n?\n")
        assert math.isnan(read_frame(sock)[0])
        assert "no device 'zz'" in read_text_frame(sock)
        assert read_frame(sock) == [pytest.approx(3.5)]
        assert read_text_frame(sock) == ""
        assert math.isnan(read_frame(sock)[0])
        assert "not utf-8 text" in read_text_frame(sock)


def test_explain_is_none_over_the_two_port_scheme() -> None:
    with serving() as (_, link):
        robot = connect(scheme="two-port", port_rx=link.two_port.port_rx,
                        port_tx=link.two_port.port_tx, timeout=10)  # fmt: skip
        with robot:
            assert math.isnan(robot.send("zz")[0])
            assert robot.explain() is None


def test_frames_after_a_clock_message_wait_for_its_answer() -> None:
    """A clock message is answered once simulated time gets there; the messages after it on
    the same connection are executed meanwhile, but their frames go out after its own."""
    with serving(speed=None) as (_, link), stream(link.stream.port) as sock:
        sock.sendall(b"w0-2\n!idle\nzz\n?\n")
        assert read_frame(sock) == [INF]
        width, count = FRAME_HEADER.unpack(sock.recv(3, socket.MSG_WAITALL))
        assert (width, count) == (8, 1)  # the idle answer (a time) before the NaN
        assert struct.unpack("<d", sock.recv(8, socket.MSG_WAITALL))[0] > 0
        assert math.isnan(read_frame(sock)[0])
        assert "no device 'zz'" in read_text_frame(sock)
