"""TCP transports: SimMeR's two-port scheme and the persistent stream protocol.

A two-port connection gets a thread of its own, so an idle or slow client never holds up the
others; the thread only reads, decodes and waits on the :class:`CommandBus`. Persistent
connections are watched by the loop thread itself (non-blocking sockets), which reads a line,
executes it and sends the reply frame with no thread hand-off (docs/protocol.md).
"""

from __future__ import annotations

import contextlib
import logging
import select
import selectors
import socket
import threading
from collections import deque
from concurrent.futures import Future
from concurrent.futures import wait as wait_futures

from simmer.protocol import (
    MAX_MESSAGE_BYTES,
    Decoded,
    decode_message,
    frame_replies,
    pack_replies,
)
from simmer.transport.bus import BusClosed, CommandBus

log = logging.getLogger("simmer.transport")

POLL = 0.05
"""How often a waiting reply connection checks whether its client hung up (seconds)."""
STREAM_PORT = 61202
"""Default port of the persistent stream protocol."""


def _listen(host: str, port: int) -> socket.socket:
    """A listening TCP socket (port 0: any free port)."""
    return socket.create_server((host, port), reuse_port=False, backlog=128)


def _hung_up(conn: socket.socket) -> bool:
    """True if the peer has closed its end (readable with no data); discards stray input."""
    try:
        readable, _, _ = select.select([conn], [], [], 0)
        if not readable:
            return False
        return conn.recv(4096) == b""
    except OSError:
        return True


class _Server:
    """A listening socket, an accept thread and one thread per connection; closes cleanly."""

    kind = "tcp"

    def __init__(self, bus: CommandBus, host: str, ports: list[int], timeout: float) -> None:
        self.bus = bus
        self.timeout = timeout
        self._stopping = threading.Event()
        self._lock = threading.Lock()
        self._conns: set[socket.socket] = set()
        self._threads: list[threading.Thread] = []
        self._wake_r, self._wake_w = socket.socketpair()
        self._listeners: list[socket.socket] = []
        try:
            for port in ports:
                self._listeners.append(_listen(host, port))
        except OSError:
            self._close_sockets()
            raise
        self.ports = [sock.getsockname()[1] for sock in self._listeners]
        self._accepter = threading.Thread(target=self._accept_loop, name=f"simmer-{self.kind}")

    def start(self) -> None:
        """Start accepting connections."""
        self._accepter.start()

    def _accept_loop(self) -> None:
        while not self._stopping.is_set():
            readable, _, _ = select.select([*self._listeners, self._wake_r], [], [])
            for sock in readable:
                if sock is self._wake_r:
                    return
                try:
                    conn, addr = sock.accept()
                except OSError:
                    continue
                conn.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
                self.accepted(conn, f"{addr[0]}:{addr[1]}", self._listeners.index(sock))

    def accepted(self, conn: socket.socket, peer: str, index: int) -> None:
        """Serve a new connection: by default in a thread of its own running :meth:`handle`."""
        thread = threading.Thread(
            target=self._serve_conn,
            args=(conn, peer, index),
            name=f"simmer-{self.kind}-{peer}",
            daemon=True,
        )
        with self._lock:
            self._conns.add(conn)
            self._threads = [t for t in self._threads if t.is_alive()]
            self._threads.append(thread)
        thread.start()

    def _serve_conn(self, conn: socket.socket, peer: str, index: int) -> None:
        try:
            self.handle(conn, peer, index)
        except BusClosed:
            pass
        except OSError as exc:
            if not self._stopping.is_set():
                log.info("%s client %s: connection lost (%s)", self.kind, peer, exc)
        finally:
            with self._lock:
                self._conns.discard(conn)
            conn.close()

    def handle(self, conn: socket.socket, peer: str, index: int) -> None:
        """Serve one connection accepted on listener ``index`` (subclasses)."""
        raise NotImplementedError

    def close(self) -> None:
        """Stop accepting, drop open connections and wait for the threads."""
        if self._stopping.is_set():
            return
        self._stopping.set()
        self._wake_w.send(b"x")
        if self._accepter.is_alive():
            self._accepter.join()
        with self._lock:
            conns = list(self._conns)
            threads = list(self._threads)
        for conn in conns:
            with contextlib.suppress(OSError):
                conn.shutdown(socket.SHUT_RDWR)
        for thread in threads:
            thread.join(timeout=2 * POLL + 1.0)
        self._close_sockets()

    def _close_sockets(self) -> None:
        for sock in self._listeners:
            sock.close()
        self._wake_r.close()
        self._wake_w.close()

    def __enter__(self) -> _Server:
        self.start()
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


class TwoPortServer(_Server):
    """SimMeR's scheme: a message arrives on ``port_rx`` (read until the client closes); its
    reply leaves on the next connection to ``port_tx`` once it is ready, then that connection
    is closed. Replies go out in the order messages arrived; a reply whose connection hangs up
    before it is sent is kept for the next one, so no reply is lost or doubled."""

    kind = "two-port"

    def __init__(
        self,
        bus: CommandBus,
        host: str = "127.0.0.1",
        port_rx: int = 61200,
        port_tx: int = 61201,
        *,
        width: int = 4,
        encoding: str = "utf-8",
        timeout: float = 300.0,
    ) -> None:
        super().__init__(bus, host, [port_rx, port_tx], timeout)
        self.port_rx, self.port_tx = self.ports
        self.width = width
        self.encoding = encoding
        self._pending: deque[Future[list[float]]] = deque()
        self._ready = threading.Condition()

    def handle(self, conn: socket.socket, peer: str, index: int) -> None:
        """Port_rx: read one message; port_tx: send the oldest unsent reply."""
        if index == 0:
            self._receive(conn, peer)
        else:
            self._reply(conn, peer)

    def _receive(self, conn: socket.socket, peer: str) -> None:
        conn.settimeout(self.timeout)
        data = bytearray()
        try:
            while len(data) <= MAX_MESSAGE_BYTES:
                chunk = conn.recv(65536)
                if not chunk:
                    break
                data += chunk
        except TimeoutError:
            log.warning("two-port client %s sent no end of message for %g s", peer, self.timeout)
            return
        if not data:
            log.debug("two-port client %s connected and sent nothing: no message", peer)
            return
        decoded = decode_message(bytes(data), self.encoding)
        with self._ready:
            self._pending.append(self.bus.submit(decoded, f"two-port {peer}"))
            self._ready.notify()

    def _reply(self, conn: socket.socket, peer: str) -> None:
        future = self._claim(conn)
        if future is None:
            return
        try:
            while not wait_futures([future], timeout=POLL).done:
                if _hung_up(conn) or self._stopping.is_set():
                    raise ConnectionAbortedError("client hung up before its reply was ready")
            conn.sendall(pack_replies(future.result(), self.width))
        except OSError:
            with self._ready:
                self._pending.appendleft(future)
                self._ready.notify()
            log.info("two-port client %s left before its reply; kept for the next one", peer)

    def _claim(self, conn: socket.socket) -> Future[list[float]] | None:
        """Wait (up to the timeout) for the oldest unclaimed reply; None if none or hung up."""
        waited = 0.0
        with self._ready:
            while not self._pending:
                if waited >= self.timeout or self._stopping.is_set() or _hung_up(conn):
                    return None
                self._ready.wait(POLL)
                waited += POLL
            return self._pending.popleft()


class StreamServer(_Server):
    """The persistent protocol: many ``\\n``-terminated messages on one connection, each
    answered in order with a frame (width byte, uint16 count, packed values).

    Its connections are not served by threads: the loop thread watches them (see
    :meth:`CommandBus.watch`), reads a message, executes it and sends the frame in one go.
    """

    kind = "stream"

    def __init__(
        self,
        bus: CommandBus,
        host: str = "127.0.0.1",
        port: int = STREAM_PORT,
        *,
        width: int = 4,
        encoding: str = "utf-8",
        timeout: float = 300.0,
    ) -> None:
        super().__init__(bus, host, [port], timeout)
        self.port = self.ports[0]
        self.width = width
        self.encoding = encoding
        self._streams: set[_Stream] = set()

    def accepted(self, conn: socket.socket, peer: str, index: int) -> None:
        """Hand the connection to the loop thread."""
        stream = _Stream(self, conn, f"stream {peer}")
        with self._lock:
            self._streams.add(stream)
        self.bus.connect(stream.client, self.kind)
        try:
            self.bus.watch(conn, stream.on_ready, selectors.EVENT_READ)
        except BusClosed:
            stream.close()

    def forget(self, stream: _Stream) -> None:
        """A connection has closed."""
        with self._lock:
            self._streams.discard(stream)
        self.bus.disconnect(stream.client)

    def close(self) -> None:
        """Stop accepting and close every connection."""
        super().close()
        with self._lock:
            streams = list(self._streams)
        for stream in streams:
            stream.close()


class _Stream:
    """One persistent-protocol connection, driven by the loop thread (non-blocking socket).

    Replies that the socket cannot take at once wait in ``outbox``; meanwhile the connection
    is not read (back-pressure on a client that sends but does not read).
    """

    def __init__(self, server: StreamServer, conn: socket.socket, client: str) -> None:
        conn.setblocking(False)
        self.server = server
        self.conn = conn
        self.client = client
        self.inbox = bytearray()
        self.searched = 0
        self.outbox = bytearray()
        self.closing = False
        self.closed = False
        self.events = selectors.EVENT_READ

    def on_ready(self, events: int) -> bool:
        """Loop thread: read and submit whole lines, or flush replies; False once closed."""
        if events & selectors.EVENT_WRITE:
            self.flush()
        elif not self.closing:
            try:
                chunk = self.conn.recv(65536)
            except BlockingIOError:
                return True
            except OSError:
                chunk = b""
            if not chunk:
                self.close()
                return False
            self.inbox += chunk
            self.submit_lines()
        return not self.closed

    def submit_lines(self) -> None:
        """Submit every complete line; an overlong line gets a NaN and ends the connection."""
        inbox = self.inbox
        while (end := inbox.find(b"\n", self.searched)) >= 0:
            self.submit(decode_message(bytes(inbox[:end]), self.server.encoding))
            del inbox[: end + 1]
            self.searched = 0
        self.searched = len(inbox)
        if len(inbox) > MAX_MESSAGE_BYTES:
            reason = f"line longer than {MAX_MESSAGE_BYTES} bytes; closing the connection"
            self.submit(Decoded(None, 1, reason))
            self.closing = True
            inbox.clear()

    def submit(self, decoded: Decoded) -> None:
        """Queue one message; its frame is sent as soon as the loop has answered it."""
        self.server.bus.submit(decoded, self.client).add_done_callback(self.reply)

    def reply(self, future: Future[list[float]]) -> None:
        """Loop thread (or a closing bus): send the reply frame, keeping order."""
        if self.closed:
            return
        if future.exception() is not None:
            self.close()
            return
        self.outbox += frame_replies(future.result(), self.server.width)
        self.flush()

    def flush(self) -> None:
        """Send what the socket takes now; watch for writability while anything is left."""
        try:
            sent = self.conn.send(self.outbox) if self.outbox else 0
        except BlockingIOError:
            sent = 0
        except OSError:  # the client has gone
            self.close()
            return
        del self.outbox[:sent]
        if not self.outbox and self.closing:
            self.close()
            return
        events = selectors.EVENT_WRITE if self.outbox else selectors.EVENT_READ
        if events != self.events:
            self.events = events
            try:
                self.server.bus.watch(self.conn, self.on_ready, events)
            except BusClosed:
                self.close()

    def close(self) -> None:
        """Stop watching and close the socket (any thread)."""
        if self.closed:
            return
        self.closed = True
        self.server.bus.unwatch(self.conn)
        self.conn.close()
        self.server.forget(self)
