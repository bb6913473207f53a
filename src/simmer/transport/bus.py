"""The one door into the simulation for every transport (DESIGN §3).

Transport threads never touch a :class:`~simmer.world.Simulation`. They hand each received
message to a :class:`CommandBus` and get a :class:`~concurrent.futures.Future` of its replies;
the loop thread (:class:`simmer.runner.Runner`) takes requests off the bus between steps,
executes them and fulfils the futures.
"""

from __future__ import annotations

import queue
import threading
from concurrent.futures import Future
from dataclasses import dataclass, field

from simmer.errors import SimmerError
from simmer.protocol import Decoded


class BusClosed(SimmerError):
    """The simulation loop has stopped; no more messages will be answered."""


@dataclass(frozen=True)
class Request:
    """One received message, who sent it, and the slot its replies go into."""

    decoded: Decoded
    client: str
    future: Future[list[float]] = field(default_factory=Future)


class CommandBus:
    """A thread-safe queue of requests, plus the list of connected clients.

    Any thread may :meth:`submit`; only the loop thread may :meth:`get`.
    """

    def __init__(self) -> None:
        self._queue: queue.SimpleQueue[Request] = queue.SimpleQueue()
        self._lock = threading.Lock()
        self._closed = False
        self._clients: dict[str, str] = {}

    def submit(self, message: Decoded | str, client: str) -> Future[list[float]]:
        """Queue a message (text or already-decoded bytes); the future holds its replies."""
        decoded = Decoded(message) if isinstance(message, str) else message
        request = Request(decoded, client)
        with self._lock:
            if self._closed:
                request.future.set_exception(BusClosed("the simulation has stopped"))
            else:
                self._queue.put(request)
        return request.future

    def get(self, timeout: float | None = None) -> Request | None:
        """Next request, waiting up to ``timeout`` seconds (0: don't wait); None if none came."""
        try:
            if timeout is not None and timeout <= 0:
                return self._queue.get_nowait()
            return self._queue.get(timeout=timeout)
        except queue.Empty:
            return None

    def pending(self) -> bool:
        """True if a request is waiting (cheap enough to ask between every step)."""
        return not self._queue.empty()

    def close(self) -> None:
        """Refuse new messages and fail the queued ones with :class:`BusClosed`."""
        with self._lock:
            self._closed = True
        while (request := self.get(0)) is not None:
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
