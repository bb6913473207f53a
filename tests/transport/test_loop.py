"""The loop alone (``SelectorLoop``), with no queue of requests: it runs ready sockets'
callbacks and due timers, ends its wait on a wake-up, on ``end_wait`` from a callback or when
its owner has work (``pending``), and refuses to watch once closed. The loop is turned by hand
in the test's thread."""

from __future__ import annotations

import selectors
import socket
import threading
from collections.abc import Iterator

import pytest

from simmer.errors import BusClosed
from simmer.transport.loop import SelectorLoop

from helpers import DEADLINE

pytestmark = pytest.mark.timeout(60)


@pytest.fixture
def loop() -> Iterator[SelectorLoop]:
    loop = SelectorLoop()
    yield loop
    loop.close()


def test_a_due_timer_runs_in_the_wait_and_a_cancelled_one_does_not(loop: SelectorLoop) -> None:
    ran: list[str] = []
    loop.call_later(0, lambda: ran.append("due"))
    loop.call_later(0, lambda: ran.append("cancelled")).cancel()
    loop.wait(DEADLINE)  # the timers' wake-up ends it
    assert ran == ["due"]


def test_an_interrupt_from_another_thread_ends_the_wait(loop: SelectorLoop) -> None:
    other = threading.Thread(target=loop.interrupt)
    other.start()
    loop.wait(DEADLINE)
    other.join()


def test_the_wait_does_not_sleep_while_its_owner_has_work(loop: SelectorLoop) -> None:
    asked: list[bool] = []

    def pending() -> bool:
        asked.append(True)
        return True

    loop.wait(DEADLINE, pending)
    assert asked


def test_a_callback_runs_in_the_loop_thread_and_may_end_the_wait(loop: SelectorLoop) -> None:
    ours, theirs = socket.socketpair()
    seen: list[tuple[bool, bytes]] = []

    def ready(events: int) -> bool:
        seen.append((loop.in_callbacks(), ours.recv(16)))
        loop.end_wait()
        return True

    with ours, theirs:
        loop.watch(ours, ready, selectors.EVENT_READ)
        theirs.sendall(b"u0\n")
        loop.wait(DEADLINE)
        loop.unwatch(ours)
    assert seen == [(True, b"u0\n")]
    assert not loop.in_callbacks()


def test_a_failing_callback_is_unwatched_and_its_owner_told(loop: SelectorLoop) -> None:
    ours, theirs = socket.socketpair()
    told: list[Exception] = []

    def ready(events: int) -> bool:
        raise OSError("gone")

    with ours, theirs:
        loop.watch(ours, ready, selectors.EVENT_READ, told.append)
        theirs.sendall(b"x")
        loop.wait(0)
        loop.wait(0)  # not watched any more: the callback is not run twice
    assert [str(error) for error in told] == ["gone"]


def test_a_closed_loop_refuses_to_watch_and_ignores_wake_ups(loop: SelectorLoop) -> None:
    loop.close()
    assert loop.closed
    loop.interrupt()
    loop.wake_from_signal()
    assert loop.call_later(0, lambda: None).cancelled
    ours, theirs = socket.socketpair()
    with ours, theirs, pytest.raises(BusClosed):
        loop.watch(ours, lambda events: True, selectors.EVENT_READ)
