"""The loop thread's wait: a ``select`` over a wake-up pipe and the sockets transports watch,
and a heap of timers (DESIGN §3).

:class:`SelectorLoop` knows nothing of messages: a watched socket's callback runs in the loop
thread (so a transport can read, have a message answered and reply with no thread hand-off),
:meth:`SelectorLoop.call_later` runs a callback there after a delay (timeouts, back-off), and
:meth:`SelectorLoop.interrupt` ends a wait early. What is queued for the loop is the
:class:`~simmer.transport.request_queue.RequestQueue`'s business; the two are put together in
:class:`~simmer.transport.bus.CommandBus`.

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
import selectors
import threading
import time
import weakref
from collections.abc import Callable
from typing import TYPE_CHECKING

from simmer.errors import BusClosed

if TYPE_CHECKING:
    from _typeshed import FileDescriptorLike, HasFileno

__all__ = ["ErrorHandler", "SelectorLoop", "Timer", "Watcher"]

log = logging.getLogger("simmer.transport")

Watcher = Callable[[int], bool]
"""Called in the loop thread with the ready ``selectors`` events; return False to stop watching."""
ErrorHandler = Callable[[Exception], None]
"""Called in the loop thread when a watcher raised (the socket is no longer watched)."""


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


def _idle() -> bool:
    return False


class SelectorLoop:
    """Watched sockets, timers and the wait that serves them.

    Any thread may :meth:`watch`, :meth:`unwatch`, :meth:`call_later` and :meth:`interrupt`;
    only the loop thread may :meth:`wait`.
    """

    def __init__(self) -> None:
        self._lock = threading.Lock()
        """Guards ``_closed`` against a write to the wake-up pipe as it is closed."""
        self._closed = False
        self._dispatching = 0
        """The thread running :meth:`wait`'s callbacks (0: none)."""
        self._settled = True
        """False once a callback in this round asked the wait to end (:meth:`end_wait`)."""
        self._selector = selectors.DefaultSelector()
        self._watch_lock = threading.RLock()
        self._timer_lock = threading.Lock()
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

    @property
    def closed(self) -> bool:
        """True once :meth:`close` has been called."""
        return self._closed

    def in_callbacks(self) -> bool:
        """Whether the calling thread is the loop thread running a ready socket's callback
        (its wait ends, or goes on, once the callbacks are done: no wake-up is needed)."""
        return self._dispatching == threading.get_ident()

    def end_wait(self) -> None:
        """Loop thread, in a callback: end the current :meth:`wait` once this round of
        callbacks is done (the loop has something to do)."""
        self._settled = False

    def interrupt(self) -> None:
        """Wake the loop thread from its wait now (any thread may ask), so it notices at once
        something decided outside it, such as a stop request or a queued request."""
        with self._lock:
            if not self._closed:
                self._wake()

    def _wake(self) -> None:
        """End the wait (caller holds ``_lock`` and the loop is open)."""
        with contextlib.suppress(BlockingIOError):  # pipe full: a wake-up is pending anyway
            os.write(self._wake_w, b"\0")

    def wake_from_signal(self) -> None:
        """Wake the loop thread from a signal handler: without a lock (the code the signal
        interrupted may hold it); nothing once the loop is closed (its pipe is gone)."""
        if not self._closed:
            with contextlib.suppress(OSError):
                os.write(self._wake_w, b"\0")

    def wait(self, timeout: float, pending: Callable[[], bool] = _idle) -> None:
        """Loop thread: sleep until a watched socket is ready, a timer is due or a wake-up
        comes (at most ``timeout`` s), running the ready sockets' callbacks and due timers.

        ``pending()`` says whether the loop's owner has work waiting: then the wait does not
        sleep. While the callbacks leave it nothing to do (nothing ``pending``, no
        :meth:`end_wait`), it goes on waiting until ``timeout``, not back through the loop for
        every ready socket; a wake-up ends the wait."""
        end = time.monotonic() + max(timeout, 0.0)
        timers = self._timers
        while True:
            now = time.monotonic()
            timeout = 0.0 if pending() else end - now
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
            self._dispatching = threading.get_ident()
            self._settled = True
            try:
                woken = self._dispatch(ready)
            finally:
                self._dispatching = 0
            now = time.monotonic()
            if timers:
                self._run_timers(now)
            if woken or not (ready and self._settled) or pending():
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

    def unwatch(self, sock: HasFileno) -> None:
        """Stop watching ``sock``; once this returns its callback is not running and won't run."""
        with self._watch_lock:
            if not self._closed:
                self._unregister(sock)

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

    def close(self) -> None:
        """Stop watching, drop the timers and release the selector and the wake-up pipe."""
        with self._watch_lock, self._lock:  # the order the loop takes them in (no deadlock)
            self._closed = True
            self._release()
        with self._timer_lock:
            self._timers.clear()
