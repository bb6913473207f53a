"""TCP transports: SimMeR's two-port scheme and the persistent stream protocol.

No thread of their own: every socket (listening or connected) is non-blocking and watched by the
loop thread through :meth:`CommandBus.watch`. The loop accepts, reads a message, executes it and
sends the reply in one go, so a reply costs no thread hand-off (that is where a threaded server's
latency goes), and an idle or slow client holds nothing up: it is just a socket nobody reads.
"""

from __future__ import annotations

import logging
import selectors
import socket
import threading
from collections import deque
from collections.abc import Callable
from concurrent.futures import Future

from simmer.protocol import (
    MAX_MESSAGE_BYTES,
    Decoded,
    PackedCodec,
    ReplyCodec,
    decode_message,
    frame_replies,
)
from simmer.transport.bus import BusClosed, CommandBus

log = logging.getLogger("simmer.transport")

STREAM_PORT = 61202
"""Default port of the persistent stream protocol."""
READ = selectors.EVENT_READ
WRITE = selectors.EVENT_WRITE


class _Connection:
    """One accepted, non-blocking connection driven by the loop thread, with an outbox for
    what the socket cannot take at once (meanwhile it is not read: back-pressure)."""

    def __init__(self, server: _Server, conn: socket.socket, client: str) -> None:
        conn.setblocking(False)
        self.server = server
        self.conn = conn
        self.client = client
        self.outbox = bytearray()
        self.close_when_sent = False
        self.closed = False
        self.events = READ

    def on_ready(self, events: int) -> bool:
        """Loop thread: flush, or read what arrived; False once closed."""
        if events & WRITE:
            self.flush()
            return not self.closed
        try:
            chunk = self.conn.recv(65536)
        except BlockingIOError:
            return True
        except OSError:
            chunk = b""
        self.received(chunk)
        return not self.closed

    def opened(self) -> None:
        """Called once the loop watches the connection (subclasses may start work here)."""

    def received(self, chunk: bytes) -> None:
        """Handle received bytes (``b""``: the client closed its end)."""
        raise NotImplementedError

    def send(self, data: bytes) -> None:
        """Queue bytes and send what the socket takes now."""
        self.outbox += data
        self.flush()

    def flush(self) -> None:
        """Send what the socket takes; watch for writability while anything is left."""
        if self.closed:
            return
        try:
            sent = self.conn.send(self.outbox) if self.outbox else 0
        except BlockingIOError:
            sent = 0
        except OSError:  # the client has gone
            self.close()
            return
        del self.outbox[:sent]
        if not self.outbox and self.close_when_sent:
            self.close()
            return
        events = WRITE if self.outbox else READ
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


class _Server:
    """Listening sockets watched by the loop; tracks connections so :meth:`close` is clean."""

    kind = "tcp"

    def __init__(self, bus: CommandBus, host: str, ports: list[int]) -> None:
        self.bus = bus
        self._lock = threading.Lock()
        self._connections: set[_Connection] = set()
        self._listeners: list[socket.socket] = []
        self._closed = False
        try:
            for port in ports:
                listener = socket.create_server((host, port), backlog=128)
                listener.setblocking(False)
                self._listeners.append(listener)
        except OSError:
            self.close()
            raise
        self.ports = [sock.getsockname()[1] for sock in self._listeners]

    def start(self) -> None:
        """Start accepting connections (the loop must be running to serve them)."""
        for index, listener in enumerate(self._listeners):
            self.bus.watch(listener, self._acceptor(index), READ)

    def _acceptor(self, index: int) -> Callable[[int], bool]:
        return lambda _events: self._accept(index)

    def _accept(self, index: int) -> bool:
        try:
            conn, addr = self._listeners[index].accept()
        except BlockingIOError:
            return True
        except OSError as exc:
            log.warning("%s: accept failed: %s", self.kind, exc)
            return True
        conn.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        connection = self.connection(conn, f"{addr[0]}:{addr[1]}", index)
        with self._lock:
            self._connections.add(connection)
        try:
            self.bus.watch(conn, connection.on_ready, READ)
        except BusClosed:
            connection.close()
            return False
        connection.opened()
        return True

    def connection(self, conn: socket.socket, peer: str, index: int) -> _Connection:
        """The handler of a connection accepted on listener ``index`` (subclasses)."""
        raise NotImplementedError

    def forget(self, connection: _Connection) -> None:
        """A connection has closed."""
        with self._lock:
            self._connections.discard(connection)

    def close(self) -> None:
        """Stop accepting and close every connection."""
        if self._closed:
            return
        self._closed = True
        for listener in self._listeners:
            self.bus.unwatch(listener)
            listener.close()
        with self._lock:
            connections = list(self._connections)
        for connection in connections:
            connection.close()

    def __enter__(self) -> _Server:
        self.start()
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


class _Pending:
    """A two-port message waiting for its reply connection: what was asked, and its replies."""

    __slots__ = ("decoded", "future")

    def __init__(self, decoded: Decoded, future: Future[list[float]]) -> None:
        self.decoded = decoded
        self.future = future


class TwoPortServer(_Server):
    """SimMeR's scheme: a message arrives on ``port_rx`` (everything until the client closes);
    its reply leaves on the next connection to ``port_tx`` once it is ready, then that
    connection is closed. Replies go out in the order messages arrived; a reply connection that
    hangs up before its reply is sent does not consume it, so no reply is lost or doubled.

    ``codec`` decides the bytes both ways: packed floats (SimMeR v1.0/v1.1) or SimMeR v1.2's
    framed text, whose message with no complete frame gets its reply connection closed with
    nothing sent, as the original did."""

    kind = "two-port"

    def __init__(
        self,
        bus: CommandBus,
        host: str = "127.0.0.1",
        port_rx: int = 61200,
        port_tx: int = 61201,
        *,
        codec: ReplyCodec | None = None,
    ) -> None:
        super().__init__(bus, host, [port_rx, port_tx])
        self.port_rx, self.port_tx = self.ports
        self.codec: ReplyCodec = codec if codec is not None else PackedCodec()
        self.unclaimed: deque[_Pending] = deque()  # replies nobody has asked for yet
        self.waiting: deque[_ReplyConnection] = deque()  # reply connections with no reply yet

    def connection(self, conn: socket.socket, peer: str, index: int) -> _Connection:
        """A message connection (port_rx) or a reply connection (port_tx)."""
        if index == 0:
            return _MessageConnection(self, conn, f"two-port {peer}")
        return _ReplyConnection(self, conn, f"two-port {peer}")

    def match(self) -> None:
        """Loop thread: give the oldest unclaimed replies to the oldest waiting connections."""
        while self.unclaimed and self.waiting:
            self.waiting.popleft().claim(self.unclaimed.popleft())


class _MessageConnection(_Connection):
    """Two-port ``port_rx``: collect the message until the client closes, then submit it."""

    def __init__(self, server: TwoPortServer, conn: socket.socket, client: str) -> None:
        super().__init__(server, conn, client)
        self.two_port = server
        self.data = bytearray()

    def received(self, chunk: bytes) -> None:
        """Collect; at the end (or past the size limit) submit the message and close."""
        self.data += chunk
        if chunk and len(self.data) <= MAX_MESSAGE_BYTES:
            return
        self.close()
        if not self.data:
            log.debug("%s connected and sent nothing: no message", self.client)
            return
        decoded = self.two_port.codec.decode(bytes(self.data))
        future = self.server.bus.submit(decoded, self.client)
        self.two_port.unclaimed.append(_Pending(decoded, future))
        self.two_port.match()


class _ReplyConnection(_Connection):
    """Two-port ``port_tx``: wait for a reply, send it, close."""

    def __init__(self, server: TwoPortServer, conn: socket.socket, client: str) -> None:
        super().__init__(server, conn, client)
        self.two_port = server
        self.reply: _Pending | None = None

    def opened(self) -> None:
        """Queue up for the next reply."""
        self.two_port.waiting.append(self)
        self.two_port.match()

    def claim(self, reply: _Pending) -> None:
        """This connection will carry ``reply`` once it is ready."""
        self.reply = reply
        reply.future.add_done_callback(lambda _future: self.ready(reply))

    def ready(self, reply: _Pending) -> None:
        """The reply exists (loop thread): send it and close."""
        if reply is not self.reply or self.closed:
            return
        if reply.future.exception() is not None:
            self.close()
            return
        self.close_when_sent = True
        self.send(self.two_port.codec.encode(reply.decoded, reply.future.result()))

    def received(self, chunk: bytes) -> None:
        """Stray bytes are ignored; end of stream means the client left."""
        if not chunk:
            self.close()

    def close(self) -> None:
        """Close; an unsent reply goes back to the front of the queue for the next reader."""
        if self.closed:
            return
        reply, self.reply = self.reply, None
        unsent = reply is not None and not (self.close_when_sent and not self.outbox)
        super().close()
        if self in self.two_port.waiting:
            self.two_port.waiting.remove(self)
        if unsent and reply is not None and not self.server.bus.closed:
            log.info("%s left before its reply was sent; kept for the next one", self.client)
            self.two_port.unclaimed.appendleft(reply)
            self.two_port.match()


class StreamServer(_Server):
    """The persistent protocol: many ``\\n``-terminated messages on one connection, each
    answered in order with a frame (width byte, uint16 count, packed values)."""

    kind = "stream"

    def __init__(
        self,
        bus: CommandBus,
        host: str = "127.0.0.1",
        port: int = STREAM_PORT,
        *,
        width: int = 4,
        encoding: str = "utf-8",
    ) -> None:
        super().__init__(bus, host, [port])
        self.port = self.ports[0]
        self.width = width
        self.encoding = encoding

    def connection(self, conn: socket.socket, peer: str, index: int) -> _Connection:
        """A persistent connection, listed among the bus's clients while open."""
        stream = _StreamConnection(self, conn, f"stream {peer}")
        self.bus.connect(stream.client, self.kind)
        return stream

    def forget(self, connection: _Connection) -> None:
        """A connection has closed: no longer a client."""
        super().forget(connection)
        self.bus.disconnect(connection.client)


class _StreamConnection(_Connection):
    """One persistent-protocol connection: lines in, frames out, in order."""

    def __init__(self, server: StreamServer, conn: socket.socket, client: str) -> None:
        super().__init__(server, conn, client)
        self.stream = server
        self.inbox = bytearray()
        self.searched = 0
        self.ended = False  # an overlong line: no more input; close after its reply
        self.last: Future[list[float]] | None = None

    def received(self, chunk: bytes) -> None:
        """Submit every complete line; an overlong line gets a NaN and ends the connection."""
        if not chunk:
            self.close()
            return
        if self.ended:
            return
        inbox = self.inbox
        inbox += chunk
        while (end := inbox.find(b"\n", self.searched)) >= 0:
            self.submit(decode_message(bytes(inbox[:end]), self.stream.encoding))
            del inbox[: end + 1]
            self.searched = 0
        self.searched = len(inbox)
        if len(inbox) > MAX_MESSAGE_BYTES:
            reason = f"line longer than {MAX_MESSAGE_BYTES} bytes; closing the connection"
            self.ended = True
            self.last = self.submit(Decoded(None, 1, reason))
            inbox.clear()

    def submit(self, decoded: Decoded) -> Future[list[float]]:
        """Queue one message; its frame is sent as soon as the loop has answered it."""
        future = self.server.bus.submit(decoded, self.client)
        future.add_done_callback(self.reply)
        return future

    def reply(self, future: Future[list[float]]) -> None:
        """Loop thread (or a closing bus): send the reply frame; futures complete in order."""
        if self.closed:
            return
        if future.exception() is not None:
            self.close()
            return
        self.close_when_sent = future is self.last
        self.send(frame_replies(future.result(), self.stream.width))
