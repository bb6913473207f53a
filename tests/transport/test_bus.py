"""Answering a message in the socket's callback (``CommandBus.request(now=True)``): only in the
loop thread, only with nothing queued ahead of it, never one client's whole pipeline at once;
the bus's wait goes on while callbacks only answer and ends when the loop has work. The loop is
turned by hand in the test's thread (it owns the simulation), so every step is deterministic."""

from __future__ import annotations

import logging
import math
import select
import selectors
import socket
import threading
from collections.abc import Callable, Iterator
from contextlib import contextmanager

import pytest

from link_support import read_frame, read_text_frame
from simmer.protocol import ClockText, CommandText
from simmer.runner import Runner
from simmer.transport.bus import CommandBus, Request
from simmer.transport.tcp import REMEMBERED, REMEMBERED_BYTES, StreamServer, _StreamConnection

from helpers import DEADLINE, POLL, make_sim

pytestmark = pytest.mark.timeout(60)


# ------------------------------------------------------------------------- the bus alone


def answered(value: float, calm: bool = True) -> Callable[[Request], bool]:
    """An ``answer_with`` handler that completes every request with ``[value]``."""

    def answer(request: Request) -> bool:
        request.future.set_result([value])
        return calm

    return answer


@pytest.fixture
def bus() -> Iterator[CommandBus]:
    bus = CommandBus()
    yield bus
    bus.close()


def asked_in_a_callback(bus: CommandBus) -> list[Request]:
    """One turn of the loop's wait in which a socket's callback asks for ``u0`` to be answered
    ``now``; the requests it made."""
    ours, theirs = socket.socketpair()
    asked: list[Request] = []

    def ready(_events: int) -> bool:
        ours.recv(100)
        asked.append(bus.request("u0", "client", now=True))
        return True

    with ours, theirs:
        bus.watch(ours, ready, selectors.EVENT_READ)
        theirs.sendall(b"u0\n")
        select.select([ours], [], [], DEADLINE)
        bus.wait(DEADLINE)
    return asked


def test_a_request_asked_now_in_a_callback_is_answered_before_request_returns(
    bus: CommandBus,
) -> None:
    bus.answer_with(answered(7.0, calm=False))
    ours, theirs = socket.socketpair()
    requests: list[Request] = []

    def ready(_events: int) -> bool:
        ours.recv(100)
        request = bus.request("u0", "client", now=True)
        assert request.future.done()  # before request returned
        requests.append(request)
        return True

    with ours, theirs:
        bus.watch(ours, ready, selectors.EVENT_READ)
        theirs.sendall(b"u0\n")
        bus.wait(DEADLINE)
    assert [r.future.result() for r in requests] == [[7.0]]
    assert bus.queued == 0


def test_a_request_asked_now_never_overtakes_one_queued_before_it(bus: CommandBus) -> None:
    bus.answer_with(answered(7.0))
    first = bus.submit("w0-1", "another client")  # queued from this thread: wakes the loop
    asked = asked_in_a_callback(bus)  # the wait ends at once: a request is queued
    assert len(asked) == 1
    assert not asked[0].future.done()
    queued = [bus.get(), bus.get()]
    assert queued[0] is not None
    assert queued[0].future is first
    assert queued[1] is asked[0]
    assert bus.get() is None


def test_now_is_only_honoured_in_the_loops_callbacks_and_with_an_answerer(
    bus: CommandBus,
) -> None:
    request = bus.request("u0", "client", now=True)  # this thread is not in the loop's wait
    assert not request.future.done()
    assert bus.queued == 1
    bus.get()
    asked = asked_in_a_callback(bus)  # in a callback, but nobody answers at once
    assert not asked[0].future.done()
    assert bus.queued == 1


@contextmanager
def rearming(bus: CommandBus, stop_after: int) -> Iterator[list[Request]]:
    """A watched socket whose callback asks for a message ``now``, then makes the socket
    readable again; after ``stop_after`` calls it queues a request instead (which ends any
    wait). Yields the requests asked for."""
    ours, theirs = socket.socketpair()
    asked: list[Request] = []

    def ready(_events: int) -> bool:
        ours.recv(100)
        asked.append(bus.request("u0", "client", now=True))
        if len(asked) < stop_after:
            theirs.sendall(b"u0\n")
        else:
            bus.submit("u0", "client")
        return True

    with ours, theirs:
        bus.watch(ours, ready, selectors.EVENT_READ)
        theirs.sendall(b"u0\n")
        yield asked


def test_the_wait_goes_on_while_callbacks_only_answer(bus: CommandBus) -> None:
    bus.answer_with(answered(1.0, calm=True))
    with rearming(bus, stop_after=3) as asked:
        bus.wait(DEADLINE)  # one wait: three messages answered, then one queued ends it
    assert len(asked) == 3
    assert all(r.future.done() for r in asked)
    assert bus.queued == 1


def test_the_wait_ends_when_an_answer_leaves_the_loop_work(bus: CommandBus) -> None:
    bus.answer_with(answered(1.0, calm=False))  # e.g. a clock message to settle
    with rearming(bus, stop_after=3) as asked:
        bus.wait(DEADLINE)
    assert len(asked) == 1  # the loop got back control after the first answer


# ---------------------------------------------------- the persistent protocol, loop by hand


class Loop:
    """A runner whose loop this thread turns (it owns the simulation, as ``Runner.run``
    makes the loop thread), a persistent-protocol server, and one connected client."""

    def __init__(self) -> None:
        self.runner = Runner(make_sim(), speed=1.0)
        self.bus = self.runner.bus
        self.runner.sim.own(threading.get_ident())
        self.bus.answer_with(self.runner.answer)
        self.server = StreamServer(self.bus, port=0)
        self.server.start()
        self.client = self.connect()
        self.connection = self.accepted(0)
        self.handled: list[str] = []
        handle = self.runner.handle

        def recording(request: Request) -> list[float]:
            self.handled.append(request.decoded.text or "")
            return handle(request)

        self.runner.handle = recording  # type: ignore[method-assign]

    def connect(self) -> socket.socket:
        sock = socket.create_connection(("127.0.0.1", self.server.port), timeout=DEADLINE)
        sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        return sock

    def accepted(self, index: int) -> _StreamConnection:
        self.turn_until(lambda: self.server.accepted > index, "the connection to be accepted")
        newest = max(self.server._connections, key=lambda c: c.order)
        assert isinstance(newest, _StreamConnection)
        return newest

    def turn_until(self, condition: Callable[[], object], what: str) -> int:
        """Turn the loop until ``condition``; how many requests went through the queue."""
        served = 0
        for _ in range(int(DEADLINE / POLL)):
            if condition():
                return served
            served += self.runner.serve(POLL)
        pytest.fail(f"the loop never got {what}")

    def answered(self, messages: int) -> bool:
        """The connection has taken ``messages`` lines and answered every one."""
        c = self.connection
        return c.messages == messages and not (c.in_flight or c.inbox or c.outbox)

    def close(self) -> None:
        self.client.close()
        self.server.close()
        self.runner.sim.own(None)
        self.bus.close()


@pytest.fixture
def loop() -> Iterator[Loop]:
    loop = Loop()
    yield loop
    loop.close()


def readable(sock: socket.socket) -> bool:
    return bool(select.select([sock], [], [], 0)[0])


def test_a_message_with_nothing_queued_is_answered_in_the_sockets_callback(loop: Loop) -> None:
    loop.client.sendall(b"u0\n")
    served = loop.turn_until(lambda: readable(loop.client), "a reply")
    assert served == 0  # nothing went through the queue
    assert loop.handled == ["u0"]
    (reading,) = read_frame(loop.client)
    assert 0 < reading < 433


def test_a_message_waits_behind_requests_queued_before_it(loop: Loop) -> None:
    other = loop.bus.submit("w0-0", "serial /dev/pts/9")  # another client's, already queued
    loop.client.sendall(b"u0\n")
    select.select([loop.connection.conn], [], [], DEADLINE)  # in the server's socket now
    served = loop.runner.serve(0.0)  # one turn: both are answered, the queued one first
    assert loop.handled == ["w0-0", "u0"]
    assert served == 2
    assert other.result(0) == [math.inf]
    assert read_frame(loop.client)[0] > 0


def test_a_pipeline_is_answered_in_order_the_first_line_at_once(loop: Loop) -> None:
    loop.client.sendall(b"zz\nw0-0\nu0\n")
    served = loop.turn_until(lambda: loop.answered(3), "every line answered")
    assert loop.handled == ["zz", "w0-0", "u0"]
    assert served == 2  # the first at once, the rest through the queue (one client's turn)
    nan, stop, reading = (read_frame(loop.client) for _ in range(3))
    assert math.isnan(nan[0])
    assert stop == [math.inf]
    assert 0 < reading[0] < 433


def test_explain_after_a_message_answered_at_once_gives_its_reasons(loop: Loop) -> None:
    loop.client.sendall(b"zz\n")
    assert loop.turn_until(lambda: readable(loop.client), "a reply") == 0
    assert math.isnan(read_frame(loop.client)[0])
    loop.client.sendall(b"?\n")
    loop.turn_until(lambda: readable(loop.client), "the reasons")
    assert "no device 'zz'" in read_text_frame(loop.client)


def test_a_failure_answering_at_once_closes_that_connection_only(
    loop: Loop, caplog: pytest.LogCaptureFixture
) -> None:
    caplog.set_level(logging.ERROR)
    handle = loop.runner.handle

    def failing(request: Request) -> list[float]:
        if request.decoded.text == "u0":
            raise RuntimeError("the sensor's code broke")
        return handle(request)

    loop.runner.handle = failing  # type: ignore[method-assign]
    loop.client.sendall(b"u0\n")
    loop.turn_until(lambda: loop.connection.closed, "the connection closed")
    assert loop.client.recv(10) == b""
    assert "the sensor's code broke" in caplog.text
    with loop.connect() as other:  # everyone else is still served
        connection = loop.accepted(1)
        other.sendall(b"w0-0\n")
        assert loop.turn_until(lambda: readable(other), "a reply") == 0
        assert read_frame(other) == [math.inf]
    assert not connection.closed


def test_a_clock_message_answered_at_once_is_settled_by_the_loop(loop: Loop) -> None:
    loop.client.sendall(b"!idle\n")  # nothing moves: answered when the loop settles waits
    loop.turn_until(lambda: readable(loop.client), "the idle answer")
    (when,) = read_frame(loop.client)
    assert when == pytest.approx(loop.runner.sim.time)


def test_answer_says_whether_the_loop_has_work_left() -> None:
    runner = Runner(make_sim(), speed=1.0)
    plain = Request(CommandText("u0", 1, tuple(runner.sim.parse("u0")), size=3), "client")
    assert runner.answer(plain) is True
    assert plain.future.result()[0] > 0
    clock = Request(ClockText("!sleep 1", size=9), "client")
    assert runner.answer(clock) is False
    assert not clock.future.done()


# ------------------------------------------------------------------- decodings kept


def test_repeated_lines_decode_once_and_what_is_kept_is_bounded(bus: CommandBus) -> None:
    server = StreamServer(bus, port=0)
    with server:
        first = server.decode(b"u0,w0-6")
        assert server.decode(b"u0,w0-6") is first
        assert first.size == len(b"u0,w0-6\n")
        assert first.count == 2
        long = b"u0," * REMEMBERED_BYTES
        assert server.decode(long).count == REMEMBERED_BYTES + 1
        assert long not in server.remembered
        for n in range(REMEMBERED + 10):
            assert server.decode(b"w0-%d" % n).commands[0].value == n
        assert len(server.remembered) <= REMEMBERED
        assert isinstance(server.decode(b"!sleep 1"), ClockText)


def test_a_lenient_server_keeps_its_own_decodings(bus: CommandBus) -> None:
    strict = StreamServer(bus, port=0)
    lenient = StreamServer(bus, port=0, lenient=True)
    with strict, lenient:
        assert strict.decode(b"w0x6").commands[0].error is not None
        assert lenient.decode(b"w0x6").commands[0].value == 6


# ------------------------------------------------------------- the loop thread decides


@pytest.mark.parametrize("lockstep", [False, True])
def test_the_loop_answers_in_callbacks_in_real_time_and_never_in_lockstep(lockstep: bool) -> None:
    """In real time the loop hands the bus its way to answer at once; in lockstep it takes one
    request at a time between steps, so nothing is answered inside the bus's wait."""
    runner = Runner(make_sim(), speed=None if lockstep else 1.0, lockstep=lockstep)
    inside: list[bool] = []
    waiting = threading.local()
    wait, handle = runner.bus.wait, runner.handle

    def watched_wait(timeout: float) -> None:
        waiting.now = True
        try:
            wait(timeout)
        finally:
            waiting.now = False

    def recording(request: Request) -> list[float]:
        inside.append(getattr(waiting, "now", False))
        return handle(request)

    runner.bus.wait = watched_wait  # type: ignore[method-assign]
    runner.handle = recording  # type: ignore[method-assign]
    stop = threading.Event()
    thread = threading.Thread(target=runner.run, kwargs={"stop_event": stop})
    with StreamServer(runner.bus, port=0) as server:
        thread.start()
        try:
            with socket.create_connection(("127.0.0.1", server.port), timeout=DEADLINE) as sock:
                for _ in range(3):
                    sock.sendall(b"w0-0\n")
                    assert read_frame(sock) == [math.inf]
        finally:
            stop.set()
            thread.join()
            runner.bus.close()
    assert inside == [not lockstep] * 3
