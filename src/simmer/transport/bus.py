"""The one door into the simulation for every transport (DESIGN §3).

Transport threads never touch a :class:`~simmer.world.Simulation`. They hand each received
message to a :class:`CommandBus` and get a :class:`Reply` (a light future) of its replies;
the loop thread (:class:`simmer.runner.Runner`) takes requests off the bus between steps,
executes them and fulfils the futures.

The bus is two parts, each with one job: :class:`~simmer.transport.loop.SelectorLoop` (the
loop's wait: watched sockets, timers, wake-ups) and
:class:`~simmer.transport.request_queue.RequestQueue` (the requests for the loop, the answer
at once in a socket's callback, the clients for the HUD). The loop sleeps in
:meth:`CommandBus.wait`; a watched socket's callback runs in the loop thread itself, so a
transport can read a message and have it executed and answered with no thread hand-off at all
(the persistent protocol does this: it is where its latency goes).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING, Protocol

from simmer.protocol import Decoded
from simmer.transport.loop import ErrorHandler, SelectorLoop, Timer, Watcher
from simmer.transport.request_queue import Reply, Request, RequestQueue

if TYPE_CHECKING:
    from _typeshed import HasFileno

__all__ = [
    "ByteCounter",
    "CommandBus",
    "ErrorHandler",
    "Reply",
    "Request",
    "Timer",
    "Watcher",
]


class ByteCounter(Protocol):
    """Where a transport reports the bytes of a program's messages it reads and sets aside
    (text outside frames, a ``?`` line): the run's clock (:class:`simmer.clock.Clock`), which
    a clock message's `` @N`` waits on (see :func:`simmer.protocol.parse_clock`); and the
    bytes it sends and the replies it holds, which a clock message's `` +`` asks for."""

    def took(self, size: int) -> None:
        """Count ``size`` bytes as taken (any thread)."""
        ...

    def gave(self, size: int) -> None:
        """Count ``size`` bytes sent to a client (any thread)."""
        ...

    def owes(self, count: Callable[[], int]) -> None:
        """``count()`` says how many replies wait to be collected (loop thread)."""
        ...


class CommandBus:
    """The loop's wait (:attr:`loop`) and its queue of requests (:attr:`requests`), put
    together: what transports and the runner are given.

    Any thread may :meth:`submit`, :meth:`watch`, :meth:`unwatch` and :meth:`call_later`;
    only the loop thread may :meth:`get` and :meth:`wait`.
    """

    def __init__(self) -> None:
        self.loop = SelectorLoop()
        self.requests = RequestQueue(self.loop)

    # ---------------------------------------------------------------- the queue's side

    def submit(self, message: Decoded | str, client: str) -> Reply[list[float]]:
        """Queue a message (text or already-decoded bytes); the future holds its replies."""
        return self.requests.submit(message, client)

    def request(self, message: Decoded | str, client: str, *, now: bool = False) -> Request:
        """Queue a message, or answer it at once in a socket's callback
        (:meth:`RequestQueue.request`)."""
        return self.requests.request(message, client, now=now)

    def answer_with(self, answer: Callable[[Request], bool] | None) -> None:
        """Loop thread: how to answer a request asked for ``now``
        (:meth:`RequestQueue.answer_with`)."""
        self.requests.answer_with(answer)

    @property
    def queued(self) -> int:
        """How many requests wait for the loop."""
        return self.requests.queued

    def get(self) -> Request | None:
        """The next queued request, or None (never waits)."""
        return self.requests.get()

    def connect(self, client: str, transport: str) -> None:
        """Record that ``client`` is connected over ``transport`` (for the HUD)."""
        self.requests.connect(client, transport)

    def disconnect(self, client: str) -> None:
        """Forget a client (no error if unknown)."""
        self.requests.disconnect(client)

    @property
    def clients(self) -> list[str]:
        """Connected clients, e.g. ``["stream 127.0.0.1:50312", "serial /dev/pts/4"]``."""
        return self.requests.clients

    # ----------------------------------------------------------------- the loop's side

    def wait(self, timeout: float) -> None:
        """Loop thread: sleep until a request is queued, a watched socket is ready or a timer
        is due (at most ``timeout`` s), running the ready sockets' callbacks and due timers
        (:meth:`SelectorLoop.wait`; it does not sleep while a request is queued)."""
        self.loop.wait(timeout, self.requests.pending)

    def watch(
        self,
        sock: HasFileno,
        callback: Watcher,
        events: int,
        on_error: ErrorHandler | None = None,
    ) -> None:
        """Run ``callback(events)`` in the loop thread whenever ``sock`` is ready
        (:meth:`SelectorLoop.watch`)."""
        self.loop.watch(sock, callback, events, on_error)

    def unwatch(self, sock: HasFileno) -> None:
        """Stop watching ``sock``; once this returns its callback is not running and won't run."""
        self.loop.unwatch(sock)

    def call_later(self, delay: float, callback: Callable[[], None]) -> Timer:
        """Run ``callback()`` in the loop thread after ``delay`` s (any thread may ask)."""
        return self.loop.call_later(delay, callback)

    def interrupt(self) -> None:
        """Wake the loop thread from its wait now (any thread may ask), so it notices at once
        something decided outside it, such as a stop request."""
        self.loop.interrupt()

    def wake_from_signal(self) -> None:
        """Wake the loop thread from a signal handler (:meth:`SelectorLoop.wake_from_signal`)."""
        self.loop.wake_from_signal()

    @property
    def closed(self) -> bool:
        """True once :meth:`close` has been called."""
        return self.loop.closed

    def close(self) -> None:
        """Refuse new messages, fail the queued ones with :class:`~simmer.errors.BusClosed`,
        stop watching and drop the timers."""
        self.loop.close()
        self.requests.close()
