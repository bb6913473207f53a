"""The one door into the simulation for every transport (DESIGN §3).

Transport threads never touch a :class:`~simmer.world.Simulation`. They hand each received
message to a :class:`CommandBus` and get a :class:`Reply` (a light future) of its replies;
the loop thread (:class:`simmer.runner.Runner`) takes requests off the bus between steps,
executes them and fulfils the futures.

The loop sleeps in :meth:`CommandBus.wait`, a ``select`` over a wake-up pipe and any sockets a
transport asked it to :meth:`~CommandBus.watch`. A watched socket's callback runs in the loop
thread itself, so a transport can read a message and have it executed and answered with no
thread hand-off at all (the persistent protocol does this: it is where its latency goes).
:meth:`CommandBus.call_later` runs a callback there after a delay (timeouts, back-off).

No exception from a callback ends the loop: a watched socket whose callback raises is no longer
watched and its ``on_error`` is told (the transports log it with the client and close that
connection); a timer's exception is logged. Everyone else goes on being served.
"""

from __future__ import annotations

import contextlib
import heapq
import itertools
import logging
import os
import queue
import selectors
import threading
import time
import weakref
from collections.abc import Callable
from typing import TYPE_CHECKING, Generic, Protocol, TypeVar

from simmer.errors import BusClosed
from simmer.protocol import CommandText, Decoded

if TYPE_CHECKING:
    from _typeshed import FileDescriptorLike, HasFileno

log = logging.getLogger("simmer.transport")

Watcher = Callable[[int], bool]
"""Called in the loop thread with the ready ``selectors`` events; return False to stop watching."""
ErrorHandler = Callable[[Exception], None]
"""Called in the loop thread when a watcher raised (the socket is no longer watched)."""


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


class ByteCounter(Protocol):
    """Where a transport reports the bytes of a program's messages it reads and sets aside
    (text outside frames, a ``?`` line): the run's clock (:class:`simmer.clock.Clock`), which
    a clock message's `` @N`` waits on (see :func:`simmer.protocol.parse_clock`)."""

    def took(self, size: int) -> None:
        """Count ``size`` bytes as taken (any thread)."""
        ...


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


class Timer:
    """A callback the loop thread runs once, at monotonic time ``when``, unless cancelled."""

    __slots__ = ("callback", "cancelled", "when")

    def __init__(self, when: float, callback: Callable[[], None]) -> None:
        self.when = when
        self.callback = callback
        self.cancelled = False

    def cancel(self) -> None:
        """Do not run it (any thread)."""
        self.cancelled = True


def _release(selector: selectors.BaseSelector, *fds: int) -> None:
    selector.close()
    for fd in fds:
        with contextlib.suppress(OSError):
            os.close(fd)


class CommandBus:
    """A thread-safe queue of requests, the loop's wait, and the list of connected clients.

    Any thread may :meth:`submit`, :meth:`watch` and :meth:`unwatch`; only the loop thread may
    :meth:`get` and :meth:`wait`.
    """

    def __init__(self) -> None:
        self._queue: queue.SimpleQueue[Request] = queue.SimpleQueue()
        self._lock = threading.Lock()
        self._timer_lock = threading.Lock()
        self._closed = False
        self._waiting = 0
        """The thread running :meth:`wait`'s callbacks (0: none): a request it submits needs
        no wake-up, as the loop serves the queue when the callbacks are done."""
        self._answer: Callable[[Request], bool] | None = None
        self._calm = True
        """False once an answer in this round of callbacks left the loop something to do."""
        self._clients: dict[str, str] = {}
        self._selector = selectors.DefaultSelector()
        self._watch_lock = threading.RLock()
        self._timers: list[tuple[float, int, Timer]] = []
        self._timer_order = itertools.count()
        self._wake_r, self._wake_w = os.pipe()
        os.set_blocking(self._wake_r, False)
        os.set_blocking(self._wake_w, False)
        self._selector.register(self._wake_r, selectors.EVENT_READ)
        self._keys: dict[int, selectors.SelectorKey] = {}
        """Each watched socket's key by descriptor, as the selector has it (its own map costs
        four calls a look-up, and the loop looks one up per ready socket)."""
        self._release = weakref.finalize(self, _release, self._selector, self._wake_r, self._wake_w)

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
        if (
            now
            and self._answer is not None
            and self._waiting == threading.get_ident()
            and self._queue.empty()
        ):
            if not self._answer(request):
                self._calm = False
            return request
        with self._lock:
            if self._closed:
                request.future.set_exception(BusClosed("the simulation has stopped"))
                return request
            self._queue.put(request)
            if threading.get_ident() != self._waiting:
                self._wake()  # a socket callback in the loop itself: its wait ends anyway
        return request

    def answer_with(self, answer: Callable[[Request], bool] | None) -> None:
        """Loop thread: answer a request asked for ``now`` by calling ``answer`` in the
        socket's callback (None: queue every request). ``answer`` completes the request's
        future (or keeps it, for a clock message) and says whether the loop may go on
        waiting (False: it has something to do once the callbacks are done)."""
        self._answer = answer

    def interrupt(self) -> None:
        """Wake the loop thread from its wait now (any thread may ask), so it notices at once
        something decided outside it, such as a stop request."""
        with self._lock:
            if not self._closed:
                self._wake()

    def wake_from_signal(self) -> None:
        """Wake the loop thread from a signal handler: without a lock (the code the signal
        interrupted may hold it); nothing once the bus is closed (its pipe is gone)."""
        if not self._closed:
            with contextlib.suppress(OSError):
                os.write(self._wake_w, b"\0")

    def _wake(self) -> None:
        """Interrupt the loop's wait (caller holds ``_lock`` and the bus is open)."""
        with contextlib.suppress(BlockingIOError):  # pipe full: a wake-up is pending anyway
            os.write(self._wake_w, b"\0")

    @property
    def queued(self) -> int:
        """How many requests wait for the loop."""
        return self._queue.qsize()

    @property
    def closed(self) -> bool:
        """True once :meth:`close` has been called."""
        return self._closed

    def get(self) -> Request | None:
        """The next queued request, or None (never waits)."""
        try:
            return self._queue.get_nowait()
        except queue.Empty:
            return None

    def wait(self, timeout: float) -> None:
        """Loop thread: sleep until a request arrives, a watched socket is ready or a timer is
        due (at most ``timeout`` s), running the ready sockets' callbacks and due timers.

        While the callbacks only answer messages at once (:meth:`answer_with`) and the loop
        has nothing else to do, it goes on waiting until ``timeout``, not back through the
        loop for every message; a request queued, a wake-up, or an answer that leaves the
        loop something to do ends the wait."""
        end = time.monotonic() + max(timeout, 0.0)
        timers = self._timers
        while True:
            now = time.monotonic()
            timeout = 0.0 if not self._queue.empty() else end - now
            if timers:
                with self._timer_lock:
                    if timers:
                        timeout = min(timeout, timers[0][0] - now)
            try:
                ready = self._selector.select(max(timeout, 0.0))
            except ValueError:  # closed by another thread meanwhile
                if self._closed:
                    return
                raise
            self._waiting = threading.get_ident()
            self._calm = True
            try:
                woken = self._dispatch(ready)
            finally:
                self._waiting = 0
            now = time.monotonic()
            if timers:
                self._run_timers(now)
            if woken or not (ready and self._calm and self._queue.empty()):
                return
            if now >= end or self._closed:
                return

    def _dispatch(self, ready: list[tuple[selectors.SelectorKey, int]]) -> bool:
        """Loop thread: run the callbacks of the ready sockets (and drain the wake-up pipe);
        True if the loop was woken (:meth:`interrupt`)."""
        woken = False
        for key, events in ready:
            if key.fd == self._wake_r:
                woken = True
                with contextlib.suppress(BlockingIOError):
                    while os.read(self._wake_r, 4096):
                        pass
                continue
            with self._watch_lock:
                if self._closed or self._keys.get(key.fd) is not key:
                    continue  # unwatched meanwhile
                callback, on_error = key.data
                try:
                    keep = callback(events)
                except Exception as exc:
                    self._unregister(key.fileobj)
                    self._failed(on_error, exc)
                    continue
                if not keep:
                    self._unregister(key.fileobj)
        return woken

    def _unregister(self, sock: FileDescriptorLike) -> None:
        """Stop watching ``sock`` (caller holds ``_watch_lock``); no error if it is not."""
        with contextlib.suppress(KeyError, ValueError):  # it may have unwatched itself
            self._keys.pop(self._selector.unregister(sock).fd, None)

    @staticmethod
    def _failed(on_error: ErrorHandler | None, exc: Exception) -> None:
        """A watcher raised: tell its owner, or log it; never let it reach the loop."""
        if on_error is None:
            log.error("a socket's callback failed; it is no longer watched", exc_info=exc)
            return
        try:
            on_error(exc)
        except Exception:
            log.exception("handling a socket callback's failure failed too")

    def watch(
        self,
        sock: HasFileno,
        callback: Watcher,
        events: int,
        on_error: ErrorHandler | None = None,
    ) -> None:
        """Run ``callback(events)`` in the loop thread whenever ``sock`` is ready for ``events``
        (``selectors.EVENT_READ`` / ``EVENT_WRITE``); calling again changes the events. If the
        callback raises, ``sock`` is no longer watched and ``on_error`` gets the exception."""
        with self._watch_lock:
            if self._closed:
                raise BusClosed("the simulation has stopped")
            if sock.fileno() in self._keys:
                key = self._selector.modify(sock, events, (callback, on_error))
            else:
                key = self._selector.register(sock, events, (callback, on_error))
            self._keys[key.fd] = key

    def call_later(self, delay: float, callback: Callable[[], None]) -> Timer:
        """Run ``callback()`` in the loop thread after ``delay`` s (any thread may ask)."""
        timer = Timer(time.monotonic() + delay, callback)
        with self._lock:
            if self._closed:
                timer.cancel()
                return timer
            with self._timer_lock:
                heapq.heappush(self._timers, (timer.when, next(self._timer_order), timer))
            self._wake()
        return timer

    def _run_timers(self, now: float) -> None:
        """Loop thread: run the timers due at ``now``; one that raises is logged."""
        while True:
            with self._timer_lock:
                if not self._timers or self._timers[0][0] > now:
                    return
                _, _, timer = heapq.heappop(self._timers)
            if timer.cancelled or self._closed:
                continue
            try:
                timer.callback()
            except Exception:
                log.exception("a timer in the simulation loop failed")

    def unwatch(self, sock: HasFileno) -> None:
        """Stop watching ``sock``; once this returns its callback is not running and won't run."""
        with self._watch_lock:
            if not self._closed:
                self._unregister(sock)

    def close(self) -> None:
        """Refuse new messages, fail the queued ones with :class:`BusClosed`, stop watching."""
        with self._watch_lock, self._lock:  # the order the loop takes them in (no deadlock)
            self._closed = True
            self._release()
        with self._timer_lock:
            self._timers.clear()
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
