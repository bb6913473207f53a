"""Issue 9, "ways to stop or starve the simulator": each reproduction, over real loopback
sockets, a real pseudo-terminal and real ``simmer run`` processes. Nothing here waits for a
time to pass as its assertion: waits are for events, with generous deadlines."""

from __future__ import annotations

import contextlib
import logging
import math
import os
import re
import selectors
import signal
import socket
import struct
import subprocess
import sys
import threading
from collections.abc import Iterator
from pathlib import Path

import pytest
import serial

from link_support import read_frame, serving, two_port_send
from simmer.client import connect
from simmer.console import run_console
from simmer.errors import ConfigError, SimmerError
from simmer.protocol import (
    FRAME_HEADER,
    MAX_COMMANDS,
    MAX_MESSAGE_BYTES,
    Decoded,
    PackedCodec,
    frame_replies,
)
from simmer.runner import LOG_LINES_PER_SECOND, Runner, _LogBudget
from simmer.transport import CommandBus, SerialServer, StreamServer
from simmer.transport.bus import Reply
from simmer.transport.tcp import ACCEPT_BACKOFF, MAX_IN_FLIGHT, MAX_UNCLAIMED, RECV_SIZE
from simmer.world import Simulation

from helpers import default_data, let_time_pass, make_config, make_sim, wait_for

pytestmark = pytest.mark.timeout(60)


def stream(port: int) -> socket.socket:
    sock = socket.create_connection(("127.0.0.1", port), timeout=10)
    sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
    return sock


def closed_by_server(sock: socket.socket) -> bool:
    """True once the server has closed ``sock`` (whatever it sent before is read and dropped)."""
    try:
        while sock.recv(65536):
            pass
    except ConnectionResetError:
        pass
    return True


def quick_sim(timeout: float = 300.0, idle_timeout: float = 3600.0) -> Simulation:
    data = default_data()
    data["timeout"] = timeout
    data["idle_timeout"] = idle_timeout
    return make_sim(data)


@contextlib.contextmanager
def loop(runner: Runner) -> Iterator[None]:
    """Run ``runner`` in a thread until the block ends."""
    stop = threading.Event()
    thread = threading.Thread(target=runner.run, kwargs={"stop_event": stop})
    thread.start()
    try:
        yield
    finally:
        stop.set()
        thread.join()
        runner.bus.close()


# --------------------------------------------------------------------------- 1. exceptions


@pytest.mark.parametrize("encoding", ["rot13", "hex", "utf-16", "utf-32", "base64", "nope"])
def test_str_encoding_that_cannot_carry_the_protocol_is_refused(encoding: str) -> None:
    data = default_data()
    data["str_encoding"] = encoding
    with pytest.raises(ConfigError) as caught:
        make_config(data)
    assert "str_encoding" in str(caught.value)
    assert "use 'utf-8' or 'ascii'" in str(caught.value)


@pytest.mark.parametrize("encoding", ["utf-8", "ascii", "latin-1", "cp1252"])
def test_text_encodings_that_write_ascii_as_ascii_are_accepted(encoding: str) -> None:
    data = default_data()
    data["str_encoding"] = encoding
    assert make_config(data).settings.str_encoding == encoding


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


def test_an_exception_executing_a_message_fails_that_request_only(
    caplog: pytest.LogCaptureFixture,
) -> None:
    caplog.set_level(logging.ERROR)
    sim = Simulation.from_config()

    def observer(event: object) -> None:
        if getattr(event, "message", None) == "u2":
            raise RuntimeError("a faulty observer")

    sim.observers.append(observer)
    with serving(sim) as (runner, link):
        with stream(link.stream.port) as sock:
            sock.sendall(b"u2\n")
            assert closed_by_server(sock)
        assert two_port_send(link, b"u1") == [pytest.approx(3.5)]
        assert runner.bus.submit("u1", "test").result(timeout=10) == [pytest.approx(3.5)]
    assert "a faulty observer" in caplog.text


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


# --------------------------------------------------------------------------- 2. limits


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


def test_a_message_of_many_bad_commands_writes_a_few_log_lines(
    caplog: pytest.LogCaptureFixture,
) -> None:
    caplog.set_level(logging.WARNING)
    with serving() as (_, link), stream(link.stream.port) as sock:
        sock.sendall(b",".join([b"zz"] * MAX_COMMANDS) + b"\n")
        assert len(read_frame(sock)) == MAX_COMMANDS
    bad = [r for r in caplog.records if "bad command" in r.getMessage()]
    assert len(bad) <= 4
    assert f"{MAX_COMMANDS - 3} more bad commands" in caplog.text


def test_a_frame_never_says_more_values_than_its_count_can() -> None:
    assert len(frame_replies([0.0] * 0xFFFF)) == 3 + 4 * 0xFFFF
    with pytest.raises(ValueError, match="do not fit"):
        frame_replies([0.0] * 0x10000)


# --------------------------------------------------------------------------- 3. two-port


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


def test_a_client_flooding_bad_commands_gets_ten_log_lines_a_second_then_a_count(
    caplog: pytest.LogCaptureFixture,
) -> None:
    caplog.set_level(logging.WARNING, logger="simmer.runner")
    now = [0.0]  # the budget's clock: the flood takes no time, however slow the machine
    with serving(speed=None) as (runner, link), stream(link.stream.port) as sock:
        runner._log = _LogBudget(clock=lambda: now[0])
        for _ in range(400):
            sock.sendall(b"zz\n")
            assert math.isnan(read_frame(sock)[0])
        assert "more log lines" not in caplog.text  # said once the second is over
        now[0] = seconds = 1.0
        wait_for(lambda: "more log lines in one second, not written" in caplog.text, "a count")
    written = [r for r in caplog.records if "no device 'zz'" in r.getMessage()]
    held = sum(
        int(m[1])
        for r in caplog.records
        if (m := re.search(r"(\d+) more log lines in one second", r.getMessage()))
    )
    assert len(written) <= LOG_LINES_PER_SECOND * (math.ceil(seconds) + 1)
    assert len(written) == LOG_LINES_PER_SECOND  # all 400 came within one second
    assert len(written) + held == 400


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


# --------------------------------------------------------------------------- 4. descriptors


def launch(tmp_path: Path, *args: str, nofile: int | None = None) -> subprocess.Popen[bytes]:
    """``simmer run --headless`` on free ports in a subprocess, output in ``tmp_path``; waits
    until it serves."""
    limit = f"import resource; resource.setrlimit(resource.RLIMIT_NOFILE, ({nofile}, {nofile}))"
    code = "\n".join(
        [
            "import sys",
            limit if nofile else "",
            "from simmer.cli import main",
            "sys.argv = ['simmer', *sys.argv[1:]]",
            "main()",
        ]
    )
    argv = ["run", "--headless", "--port", "0", "--port-rx", "0", "--port-tx", "0", *args]
    with (tmp_path / "out").open("wb") as out, (tmp_path / "err").open("wb") as err:
        proc = subprocess.Popen([sys.executable, "-c", code, *argv], stdout=out, stderr=err)
    wait_for(lambda: "running headless" in output(tmp_path), "simmer run to start", 60)
    return proc


def output(tmp_path: Path, name: str = "out") -> str:
    return (tmp_path / name).read_text(errors="replace")


def stream_port_of(tmp_path: Path) -> int:
    line = next(li for li in output(tmp_path).splitlines() if li.startswith("persistent TCP"))
    return int(line.split(" port ")[1].split()[0])


def stop(proc: subprocess.Popen[bytes], how: int = signal.SIGTERM) -> int:
    proc.send_signal(how)
    try:
        return proc.wait(timeout=30)
    except subprocess.TimeoutExpired:
        proc.kill()
        proc.wait()
        raise


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


# --------------------------------------------------------------------------- 5. slow readers


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


# --------------------------------------------------------------------------- 6. signals, links


@pytest.mark.parametrize("how", [signal.SIGTERM, signal.SIGHUP])
def test_sigterm_and_sighup_stop_cleanly_and_remove_the_serial_link(
    tmp_path: Path, how: signal.Signals
) -> None:
    link_path = tmp_path / "robot"
    proc = launch(tmp_path, "--serial-link", str(link_path))
    try:
        assert link_path.is_symlink()
        assert stop(proc, how) == 0
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
    assert not link_path.is_symlink()
    assert not link_path.exists()
    assert "stopped" in output(tmp_path)


class _DiesWithASignal:
    """An object whose finalizer is where a stop signal lands."""

    def __del__(self) -> None:
        os.kill(os.getpid(), signal.SIGTERM)
        sum(range(1000))  # the handler runs between these bytecodes, inside the finalizer


def test_a_stop_signal_landing_in_a_finalizer_still_stops_the_run() -> None:
    """An exception raised from a finalizer is ignored by Python: once, under load, SIGTERM
    landed in one of Numba's while the handler raised KeyboardInterrupt, and the run never
    stopped. The handler now only sets the stop event and wakes the loop."""
    from simmer.serve import _stop_on_signals

    stop, woken, received = threading.Event(), [], []
    restore = _stop_on_signals(stop, lambda: woken.append(True), received)
    try:
        _DiesWithASignal()  # collected at once: the signal arrives in its __del__
    finally:
        restore()
    assert stop.is_set()
    assert woken == [True]
    assert received == ["SIGTERM"]


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


def test_cli_refuses_a_serial_link_path_that_exists(tmp_path: Path) -> None:
    path = tmp_path / "robot"
    path.symlink_to("/dev/null")
    result = subprocess.run(
        [sys.executable, "-m", "simmer", "run", "--headless", "--seconds", "0.1", "--port", "0",
         "--port-rx", "0", "--port-tx", "0", "--serial-link", str(path)],
        capture_output=True,
        text=True,
        timeout=60,
        check=False,
    )  # fmt: skip
    assert result.returncode == 1
    assert "already there" in result.stderr
    assert os.readlink(path) == "/dev/null"


# --------------------------------------------------------------------------- why NaN


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
        assert "no device 'zz'" in read_text(sock)
        assert read_frame(sock) == [pytest.approx(3.5)]
        assert read_text(sock) == ""
        assert math.isnan(read_frame(sock)[0])
        assert "not utf-8 text" in read_text(sock)


def read_text(sock: socket.socket) -> str:
    width, size = FRAME_HEADER.unpack(sock.recv(3, socket.MSG_WAITALL))
    assert width == 0
    return sock.recv(size, socket.MSG_WAITALL).decode() if size else ""


def test_explain_is_none_over_the_two_port_scheme() -> None:
    with serving() as (_, link):
        robot = connect(scheme="two-port", port_rx=link.two_port.port_rx,
                        port_tx=link.two_port.port_tx, timeout=10)  # fmt: skip
        with robot:
            assert math.isnan(robot.send("zz")[0])
            assert robot.explain() is None


def test_console_shows_why_a_reply_is_nan() -> None:
    lines = iter(["zz", "u1", "quit"])
    shown: list[str] = []
    with serving() as (_, link), connect(port=link.stream.port, timeout=10) as robot:
        run_console(robot, read=lambda _prompt: next(lines), echo=shown.append, history=False)
    text = "\n".join(shown)
    assert "why: " in text
    assert "no device 'zz' on the robot" in text
    assert text.count("why: ") == 1  # not after u1's reading


def test_a_request_carries_its_reasons() -> None:
    bus = CommandBus()
    runner = Runner(Simulation.from_config(), bus=bus)
    request = bus.request("u0,zz", "test")
    runner.serve()
    assert isinstance(request.future, Reply)
    assert request.future.result()[0] > 0
    assert len(request.reasons) == 1
    assert "no device 'zz'" in request.reasons[0]
    bus.close()
