"""What the loop thread is asked to do: received messages queued as :class:`Request` s, each
with a :class:`Reply` (a light future) its replies go into, and the clients connected, for the
HUD (DESIGN §3).

Transport threads never touch a :class:`~simmer.world.Simulation`: they hand each message to
the :class:`RequestQueue` and the loop thread (:class:`simmer.runner.Runner`) takes requests off
it between steps, executes them and fulfils the futures. The queue knows nothing of sockets or
timers: it asks the :class:`~simmer.transport.loop.SelectorLoop` it was given to wake up when
something is queued, and whether a request comes from a socket's callback in the loop thread
(which may then be answered at once, :meth:`RequestQueue.answer_with`).
"""

from __future__ import annotations

import logging
import queue
import threading
from collections.abc import Callable
from typing import TYPE_CHECKING, Generic, TypeVar

from simmer.errors import BusClosed
from simmer.protocol import CommandText, Decoded

if TYPE_CHECKING:
    from simmer.transport.loop import SelectorLoop

__all__ = ["Reply", "Request", "RequestQueue"]

log = logging.getLogger("simmer.transport")


T = TypeVar("T")
_FINISH = threading.Lock()
"""Guards a :class:`Reply`'s completion against a callback or a waiter being added at that
moment from another thread (held for a few instructions; shared by all replies)."""


class Reply(Generic[T]):
    """A slot the loop thread fills once: what :class:`concurrent.futures.Future` does for a
    request, at a fraction of its cost (no condition variable per request: a thread that
    blocks in :meth:`result` gets an event then). Callbacks run in the thread that completes
    it, or at once if it is already complete; one that raises is logged."""

    __slots__ = ("_callbacks", "_done", "_error", "_event", "_value")

    def __init__(self) -> None:
        self._done = False
        self._value: T | None = None
        self._error: BaseException | None = None
        self._callbacks: list[Callable[[Reply[T]], object]] = []
        self._event: threading.Event | None = None

    def done(self) -> bool:
        """Whether it holds a result or an exception."""
        return self._done

    def set_result(self, value: T) -> None:
        """Complete it with ``value``."""
        self._finish(value, None)

    def set_exception(self, error: BaseException) -> None:
        """Complete it with ``error`` (raised by :meth:`result`)."""
        self._finish(None, error)

    def _finish(self, value: T | None, error: BaseException | None) -> None:
        with _FINISH:
            if self._done:
                raise RuntimeError("a reply is completed once")
            self._value, self._error, self._done = value, error, True
            callbacks, self._callbacks = self._callbacks, []
        if self._event is not None:
            self._event.set()
        for callback in callbacks:
            self._call(callback)

    def _call(self, callback: Callable[[Reply[T]], object]) -> None:
        try:
            callback(self)
        except Exception:
            log.exception("a reply's callback failed")

    def add_done_callback(self, callback: Callable[[Reply[T]], object]) -> None:
        """Call ``callback(self)`` once it is complete (now, if it is)."""
        with _FINISH:
            if not self._done:
                self._callbacks.append(callback)
                return
        self._call(callback)

    def result(self, timeout: float | None = None) -> T:
        """The result, waiting up to ``timeout`` s for it (TimeoutError past it); raises the
        exception it was completed with."""
        if not self._done:
            with _FINISH:
                if not self._done and self._event is None:
                    self._event = threading.Event()
            if self._event is not None and not self._event.wait(timeout):
                raise TimeoutError("no reply yet")
        if self._error is not None:
            raise self._error
        return self._value  # type: ignore[return-value]

    def exception(self) -> BaseException | None:
        """The exception it was completed with (None: a result); only once it is done."""
        if not self._done:
            raise RuntimeError("the reply is not complete yet")
        return self._error


class Request:
    """One received message, who sent it, and the slot its replies go into (a plain slotted
    class: one is made per message, and a dataclass's would cost half a microsecond more).

    ``reasons``: why some replies are NaN, filled in by the loop before the future completes
    (the persistent protocol's ``?`` sends them). ``answer``: a text answer instead of the
    values (a localization message's, ``%maze``), filled in likewise; sent as a document
    frame."""

    __slots__ = ("answer", "client", "decoded", "future", "reasons")

    def __init__(self, decoded: Decoded, client: str) -> None:
        self.decoded = decoded
        self.client = client
        self.future: Reply[list[float]] = Reply()
        self.reasons: list[str] = []
        self.answer: list[str] = []


class RequestQueue:
    """A thread-safe queue of requests for the loop thread, and the list of connected clients.

    Any thread may :meth:`submit`; only the loop thread may :meth:`get`.
    """

    def __init__(self, loop: SelectorLoop) -> None:
        self._loop = loop
        self._queue: queue.SimpleQueue[Request] = queue.SimpleQueue()
        self._lock = threading.Lock()
        self._closed = False
        self._answer: Callable[[Request], bool] | None = None
        self._clients: dict[str, str] = {}

    def submit(self, message: Decoded | str, client: str) -> Reply[list[float]]:
        """Queue a message (text or already-decoded bytes); the future holds its replies."""
        return self.request(message, client).future

    def request(self, message: Decoded | str, client: str, *, now: bool = False) -> Request:
        """Queue a message like :meth:`submit`; the request also carries the NaN reasons.

        ``now``: a watched socket's callback asks for it to be answered before this returns,
        which the loop does if it answers that way (:meth:`answer_with`) and nothing is
        queued ahead of it; otherwise it is queued."""
        decoded = CommandText(message) if isinstance(message, str) else message
        request = Request(decoded, client)
        in_callbacks = self._loop.in_callbacks()
        if now and self._answer is not None and in_callbacks and self._queue.empty():
            if not self._answer(request):
                self._loop.end_wait()
            return request
        with self._lock:
            if self._closed:
                request.future.set_exception(BusClosed("the simulation has stopped"))
                return request
            self._queue.put(request)
            if not in_callbacks:
                self._loop.interrupt()  # a socket callback in the loop: its wait ends anyway
        return request

    def answer_with(self, answer: Callable[[Request], bool] | None) -> None:
        """Loop thread: answer a request asked for ``now`` by calling ``answer`` in the
        socket's callback (None: queue every request). ``answer`` completes the request's
        future (or keeps it, for a clock message) and says whether the loop may go on
        waiting (False: it has something to do once the callbacks are done)."""
        self._answer = answer

    @property
    def queued(self) -> int:
        """How many requests wait for the loop."""
        return self._queue.qsize()

    def pending(self) -> bool:
        """Whether a request waits for the loop (cheaper than :attr:`queued`)."""
        return not self._queue.empty()

    def get(self) -> Request | None:
        """The next queued request, or None (never waits)."""
        try:
            return self._queue.get_nowait()
        except queue.Empty:
            return None

    def close(self) -> None:
        """Refuse new messages and fail the queued ones with :class:`BusClosed`."""
        with self._lock:
            self._closed = True
        while (request := self.get()) is not None:
            request.future.set_exception(BusClosed("the simulation has stopped"))

    # --------------------------------------------------------------- clients (for the HUD)

    def connect(self, client: str, transport: str) -> None:
        """Record that ``client`` is connected over ``transport``."""
        with self._lock:
            self._clients[client] = transport

    def disconnect(self, client: str) -> None:
        """Forget a client (no error if unknown)."""
        with self._lock:
            self._clients.pop(client, None)

    @property
    def clients(self) -> list[str]:
        """Connected clients, e.g. ``["stream 127.0.0.1:50312", "serial /dev/pts/4"]``."""
        with self._lock:
            return list(self._clients)
