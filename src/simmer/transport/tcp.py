"""TCP transports: SimMeR's two-port scheme and the persistent stream protocol.

No thread of their own: every socket (listening or connected) is non-blocking and watched by the
loop thread through :meth:`CommandBus.watch`. The loop accepts, reads a message, executes it and
sends the reply in one go, so a reply costs no thread hand-off (that is where a threaded server's
latency goes), and an idle or slow client holds nothing up: it is just a socket nobody reads.

What no client can do, however it behaves:

* stop the loop: an exception while serving a connection is logged once, with the client, and
  closes that connection only;
* hold more than a bounded amount of memory: a persistent connection has at most
  :data:`MAX_IN_FLIGHT` commands waiting for the loop and is not read while replies to it wait
  to be sent (back-pressure), so what it queues is its last 64 KiB read plus the replies to
  those commands; two-port replies nobody collects are held at most ``timeout`` s, and at most
  :data:`MAX_UNCLAIMED` of them;
* hold a descriptor for ever without talking: a connection that has not sent a complete message
  (or, on ``port_tx``, has had no reply) within ``timeout`` s is closed;
* spin the loop when descriptors run out: accepting pauses for :data:`ACCEPT_BACKOFF` s at a
  time, said once, and resumes by itself.
"""

from __future__ import annotations

import contextlib
import errno
import functools
import itertools
import logging
import math
import selectors
import socket
import threading
import time
from collections import deque
from collections.abc import Callable
from dataclasses import replace

from simmer.errors import BusClosed
from simmer.ports import PORT_RX, PORT_TX, STREAM_PORT
from simmer.protocol import (
    CLOCK_PREFIX,
    EXPLAIN,
    MAX_COMMANDS,
    MAX_MESSAGE_BYTES,
    META_PREFIX,
    ClockText,
    CommandText,
    Decoded,
    LocalizationText,
    PackedCodec,
    Refused,
    Replies,
    ReplyCodec,
    decode_message,
    decode_meta,
    frame_document,
    frame_replies,
    frame_text,
    printable,
)
from simmer.transport.bus import ByteCounter, CommandBus, Reply, Request
from simmer.transport.link import Link, Wire

log = logging.getLogger("simmer.transport")

READ = selectors.EVENT_READ
WRITE = selectors.EVENT_WRITE
RECV_SIZE = 65536
"""Bytes read from a socket at a time."""

MAX_IN_FLIGHT = MAX_COMMANDS
"""Commands a persistent connection may have waiting for the loop (sent, not yet answered);
past it the connection is not read until replies go out. One message of the most commands
always fits; the loop then spends at most ~15 ms on one connection before others get a turn."""
MAX_UNCLAIMED = 256
"""Two-port replies held for reply connections that have not come yet; the oldest is dropped
past it. A lab runs a handful of clients, each with one message out at a time; 256 uncollected
messages are at most 16 MiB even if each is 64 KiB."""
ACCEPT_BACKOFF = 0.5
"""Seconds a listener is not watched after accepting failed for lack of descriptors (or
anything unexpected): retrying at once would spin the loop, and the connections already open are
served meanwhile; half a second is short beside a client's connect timeout."""
LOGGED_LINES = 3
"""Two-port log lines about one reply (dropped because another waits, v1.0/v1.1; kept because
its reply connection left) written per idle sweep (about a second); the rest are counted in
one line at the sweep. 30,000 messages nobody collected wrote 29,999 lines (5.5 MB)."""
REMEMBERED = 256
"""Persistent-protocol lines whose decoding is kept (forgotten all at once past it): a
program's repeated messages (``u0``, ``w0-6``) then cost no decoding."""
REMEMBERED_BYTES = 128
"""Longest line (with its ``\\n``) whose decoding is kept, so what is kept stays small."""
_OUT_OF_RESOURCES = {errno.EMFILE, errno.ENFILE, errno.ENOBUFS, errno.ENOMEM}


class _Connection:
    """One accepted, non-blocking connection driven by the loop thread, with an outbox for
    what the socket cannot take at once (meanwhile it is not read: back-pressure).

    ``deadline`` (monotonic) is when the idle sweep closes it; None: never (it is not waiting
    for the client, or the client is between messages)."""

    def __init__(self, server: _Server, conn: socket.socket, client: str) -> None:
        conn.setblocking(False)
        self.server = server
        self.conn = conn
        self.client = client
        self.outbox = bytearray()
        self.close_when_sent = False
        self.closed = False
        self.events = 0
        self.order = next(server.order)
        """Accept order across the server's listeners (the two-port scheme pairs by it)."""
        self.deadline: float | None = time.monotonic() + server.timeout

    def start(self) -> None:
        """Watch the connection, then let the subclass start its work."""
        self.update_events()
        if not self.closed:
            self.opened()

    def on_ready(self, events: int) -> bool:
        """Loop thread: flush, or read what arrived; False once closed."""
        if events & WRITE:
            self.flush()
        else:
            self.read()
        return not self.closed

    def read(self) -> bool:
        """Read what the kernel holds for this connection, once; False if it held nothing."""
        try:
            chunk = self.conn.recv(RECV_SIZE)
        except BlockingIOError:
            return False
        except OSError:
            chunk = b""
        self.received(chunk)
        return True

    def opened(self) -> None:
        """Called once the loop watches the connection (subclasses may start work here)."""

    def received(self, chunk: bytes) -> None:
        """Handle received bytes (``b""``: the client closed its end)."""
        raise NotImplementedError

    def reading(self) -> bool:
        """Whether to read more from the client now (subclasses may hold back)."""
        return True

    def drained(self) -> None:
        """Everything queued has been sent (subclasses may take more input now)."""

    def send(self, data: bytes) -> None:
        """Send what the socket takes now; queue the rest."""
        if self.outbox:
            self.outbox += data
            data = b""
        self.flush(data)

    def flush(self, data: bytes = b"") -> None:
        """Send what the socket takes (what is queued, or else ``data``, whose rest is queued);
        watch for writability while anything is left."""
        if self.closed:
            return
        if data or self.outbox:
            try:
                sent = self.conn.send(data or self.outbox)
            except BlockingIOError:
                sent = 0
            except OSError:  # the client has gone
                self.close()
                return
            if self.server.clock is not None:
                self.server.clock.gave(sent)
            if data:
                self.outbox += data[sent:]
            else:
                del self.outbox[:sent]
        if not self.outbox:
            if self.close_when_sent:
                self.close()
                return
            self.drained()
        self.update_events()

    def update_events(self) -> None:
        """Watch for what the connection needs now: writability while replies wait to be sent
        (nothing is read meanwhile), readability while it takes input, else nothing."""
        if self.closed:
            return
        events = WRITE if self.outbox else (READ if self.reading() else 0)
        if events == self.events:
            return
        self.events = events
        try:
            if events:
                self.server.bus.watch(self.conn, self.on_ready, events, self.failed)
            else:
                self.server.bus.unwatch(self.conn)
        except BusClosed:
            self.close()

    def guard(self, action: Callable[[], None]) -> None:
        """Run ``action`` for this connection (a reply being ready, say): if it raises, the
        connection is closed, not the loop."""
        try:
            action()
        except Exception as exc:
            self.failed(exc)

    def failed(self, exc: Exception) -> None:
        """Serving this connection raised: log it once, with the client, and close it."""
        if self.closed:
            return
        log.error("%s: internal error, closing the connection: %s", self.client, exc, exc_info=exc)
        self.close()

    def close(self) -> None:
        """Stop watching and close the socket (any thread)."""
        if self.closed:
            return
        self.closed = True
        self.deadline = None
        self.server.bus.unwatch(self.conn)
        self.conn.close()
        self.server.forget(self)


class _Server:
    """Listening sockets watched by the loop; tracks connections so :meth:`close` is clean,
    closes idle ones (see :class:`_Connection`) and backs off when accepting fails."""

    kind = "tcp"

    def __init__(
        self,
        bus: CommandBus,
        host: str,
        ports: list[int],
        timeout: float = 300.0,
        idle_timeout: float | None = None,
        clock: ByteCounter | None = None,
        listeners: list[socket.socket] | None = None,
    ) -> None:
        self.bus = bus
        self.clock = clock
        """Where the bytes sent (and any set aside) are counted (None: nowhere, a server off
        any run's clock)."""
        self.timeout = timeout
        self.idle_timeout = idle_timeout
        """Seconds a connection may sit between messages (None: no limit)."""
        self.order = itertools.count()
        self.accepted = 0
        """Connections accepted and started so far (what a test waits on)."""
        self._lock = threading.Lock()
        self._connections: set[_Connection] = set()
        self._listeners: list[socket.socket] = []
        self._paused: set[int] = set()
        self._accept_failing = False
        self._closed = False
        try:
            for port in ports if listeners is None else ():
                self._listeners.append(socket.create_server((host, port), backlog=128))
            self._listeners += listeners or []
            for listener in self._listeners:
                listener.setblocking(False)
        except OSError:
            self.close()
            raise
        self.ports = [sock.getsockname()[1] for sock in self._listeners]

    def start(self) -> None:
        """Start accepting connections (the loop must be running to serve them)."""
        for index in range(len(self._listeners)):
            self._watch_listener(index)
        self.bus.call_later(self._sweep_interval(), self._sweep)

    def _watch_listener(self, index: int) -> None:
        """Accept on listener ``index`` when it is readable; back off if that raises."""
        self.bus.watch(
            self._listeners[index],
            lambda _events: self._accept(index),
            READ,
            lambda exc: self._pause(index, exc),
        )

    def _accept(self, index: int) -> bool:
        """Loop thread: listener ``index`` is readable."""
        self.accept_one(index)
        return True

    def accept_one(self, index: int) -> bool:
        """Accept one connection on listener ``index`` if one waits; True if one was."""
        try:
            conn, addr = self._listeners[index].accept()
        except BlockingIOError:
            return False
        except OSError as exc:
            if exc.errno in _OUT_OF_RESOURCES:
                self._pause(index, exc)
            else:  # e.g. the client gave up before we got to it
                log.debug("%s: accept failed: %s", self.kind, exc)
            return False
        if self._accept_failing:
            self._accept_failing = False
            log.warning("%s: accepting connections again", self.kind)
        try:
            conn.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
            connection = self.connection(conn, f"{addr[0]}:{addr[1]}", index)
        except OSError as exc:  # reset before we got to it
            log.debug("%s: dropped a connection at once: %s", self.kind, exc)
            conn.close()
            return True
        with self._lock:
            self._connections.add(connection)
        connection.guard(connection.start)
        self.accepted += 1
        return True

    def _pause(self, index: int, exc: Exception) -> None:
        """Stop watching listener ``index`` for :data:`ACCEPT_BACKOFF` s (out of descriptors,
        or accepting raised): said once until accepting works again."""
        if index in self._paused or self._closed:
            return
        self._paused.add(index)
        self.bus.unwatch(self._listeners[index])
        if not self._accept_failing:
            self._accept_failing = True
            log.error(
                "%s: cannot accept connections (%s); retrying every %g s, said once; open "
                "connections are still served",
                self.kind,
                exc,
                ACCEPT_BACKOFF,
                exc_info=None if isinstance(exc, OSError) else exc,
            )
        self.bus.call_later(ACCEPT_BACKOFF, lambda: self._resume(index))

    def _resume(self, index: int) -> None:
        """The back-off is over: watch listener ``index`` again."""
        if self._closed:
            return
        self._paused.discard(index)
        with contextlib.suppress(BusClosed):
            self._watch_listener(index)

    def _sweep_interval(self) -> float:
        """Seconds between idle sweeps: a quarter of the shorter timeout, within 0.01 s and
        1 s."""
        shortest = min(self.timeout, self.idle_timeout or self.timeout)
        return min(1.0, max(0.01, shortest / 4))

    def _sweep(self) -> None:
        """Loop thread, every second or so: close connections past their deadline."""
        if self._closed:
            return
        try:
            now = time.monotonic()
            with self._lock:
                late = [
                    c for c in self._connections if c.deadline is not None and c.deadline <= now
                ]
            for connection in late:
                connection.close()
            if late:
                idle = f" or {self.idle_timeout:g} s between messages" if self.idle_timeout else ""
                log.info(
                    "%s: closed %d connection(s) that waited too long: %g s for a whole "
                    "message (or a reply to collect; the timeout setting)%s (idle_timeout): %s",
                    self.kind,
                    len(late),
                    self.timeout,
                    idle,
                    ", ".join(c.client for c in late[:3]) + (", ..." if len(late) > 3 else ""),
                )
            self.swept(now)
        finally:
            self.bus.call_later(self._sweep_interval(), self._sweep)

    def swept(self, now: float) -> None:
        """After each idle sweep (subclasses expire what they hold)."""

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
        self._closed = True  # its timers see it and stop
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
    """A two-port message waiting for its reply connection: what was asked, its replies, the
    accept order of its connection and when it arrived."""

    __slots__ = ("arrived", "decoded", "future", "order")

    def __init__(self, decoded: Decoded, future: Reply[list[float]], order: int) -> None:
        self.decoded = decoded
        self.future = future
        self.order = order
        self.arrived = time.monotonic()

    def replies(self) -> Replies | None:
        """What was asked and answered (None if answering failed: the simulation stopped)."""
        if self.future.exception() is not None:
            return None
        return self.decoded, self.future.result()


class TwoPortServer(_Server):
    """SimMeR's scheme: a message arrives on ``port_rx`` (everything until the client closes);
    a connection to ``port_tx`` collects replies, then is closed. ``codec`` decides the bytes
    both ways (packed floats, SimMeR v1.0/v1.1; or v1.2's framed text, whose message with no
    complete frame gets nothing back) and what a reply connection collects, as the original
    of that version did (BEHAVIOUR §6.4, docs/protocol.md):

    * v1.2 (``codec.keeps == "all"``): every reply waiting, in one frame;
    * v1.0/v1.1 (``"first"``): the first reply waiting; a reply that comes while another
      waits is dropped (logged), as the original's one-reply transmit buffer dropped it;
    * nothing waiting: the connection is closed at once with nothing sent.

    Better than the originals, a reply connection is answered only after everything already
    queued at ``port_rx`` is taken (:meth:`take_queued`: the connections waiting to be
    accepted, then every byte and close waiting to be read), and it waits for the replies
    still being computed to those messages. A client closes its message connection (or at
    least has sent its message) before it opens its reply connection, so on this machine's
    loopback its message is always among them, however busy the loop is: no timing decides
    a reply, and a client never falls one reply behind. A message connection still open then
    holds its message as it stands (the original took a message's first ``recv``); one that
    has sent nothing is no message. A reply connection never takes the reply to a message
    accepted after it. Reply connections are served in the order they came. Replies nobody
    collects are dropped after ``timeout`` s, and past :data:`MAX_UNCLAIMED` the oldest goes,
    so memory stays bounded. A reply connection that hangs up before its replies are sent does
    not consume them: the next one gets them."""

    kind = "two-port"

    def __init__(
        self,
        bus: CommandBus,
        host: str = "127.0.0.1",
        port_rx: int = PORT_RX,
        port_tx: int = PORT_TX,
        *,
        codec: ReplyCodec | None = None,
        timeout: float = 300.0,
        clock: ByteCounter | None = None,
        link_model: Link | None = None,
        listeners: list[socket.socket] | None = None,
    ) -> None:
        super().__init__(bus, host, [port_rx, port_tx], timeout, clock=clock, listeners=listeners)
        self.link_model = link_model
        """The link model its messages and replies cross (None: off)."""
        if clock is not None:
            clock.owes(lambda: len(self.pending))
        self.port_rx, self.port_tx = self.ports
        self.codec: ReplyCodec = codec if codec is not None else PackedCodec()
        self.pending: deque[_Pending] = deque()  # replies (or their futures) nobody collected
        self.receiving: dict[_MessageConnection, None] = {}  # message connections, in order
        self.waiting: deque[_ReplyConnection] = deque()  # reply connections, oldest first
        self.dropped = 0  # replies dropped since the last sweep (logged there)
        self.said = 0  # lines about one reply logged since the last sweep
        self.unsaid = 0  # and those past :data:`LOGGED_LINES`, counted at the sweep

    def connection(self, conn: socket.socket, peer: str, index: int) -> _Connection:
        """A message connection (port_rx) or a reply connection (port_tx)."""
        if index == 0:
            return _MessageConnection(self, conn, f"two-port {peer}")
        return _ReplyConnection(self, conn, f"two-port {peer}")

    def _accept(self, index: int) -> bool:
        """A reply connection is accepted only after everything queued at ``port_rx`` is
        taken, so that a client's message always comes before its reply connection."""
        if index == 1:
            self.take_queued()
        return super()._accept(index)

    def take_queued(self) -> None:
        """Loop thread: accept every message connection waiting, then read every byte and
        close waiting on each open one, until the kernel holds nothing more; a connection
        that sent something and is still open then ends its message as it stands."""
        while self.accept_one(0):
            pass
        for message in list(self.receiving):
            message.guard(message.take_queued)

    def arrived(self, decoded: Decoded, order: int, client: str) -> None:
        """Loop thread: a whole message came in; execute it and hold its reply."""
        pending = _Pending(decoded, self.bus.submit(decoded, client), order)
        self.pending.append(pending)
        while len(self.pending) > MAX_UNCLAIMED:
            self.pending.popleft()
            self.dropped += 1
        pending.future.add_done_callback(lambda _future: self._answered(pending))

    def _answered(self, pending: _Pending) -> None:
        """Loop thread (or a closing bus): a reply is ready. v1.0/v1.1 drop it if an earlier
        one still waits; then whoever can collect does."""
        if self.codec.keeps == "first" and pending in self.pending:
            earlier = itertools.takewhile(lambda p: p is not pending, self.pending)
            if any(p.future.done() for p in earlier):
                self.pending.remove(pending)
                self.say(
                    "two-port: the reply to %r is dropped: an earlier reply is still waiting "
                    "to be collected, and SimMeR v1.0/v1.1 kept only one",
                    printable(pending.decoded.text or "?"),
                )
        self.collect()

    def collect(self) -> None:
        """Loop thread: serve the waiting reply connections, oldest first, with what each
        collects (see the class doc); stop at one that must wait."""
        while self.waiting:
            reply = self.waiting[0]
            earlier = [p for p in self.pending if p.order < reply.order]
            if any(not p.future.done() for p in earlier):
                return  # answered soon: collected then
            self.waiting.popleft()
            if self.codec.keeps == "first":
                earlier = earlier[:1]
            for p in earlier:
                self.pending.remove(p)
            reply.guard(functools.partial(reply.deliver, earlier))

    def say(self, text: str, *args: object) -> None:
        """Log a line about one reply, unless :data:`LOGGED_LINES` were since the last sweep
        (then it is counted, and the count said at the sweep)."""
        if self.said < LOGGED_LINES:
            self.said += 1
            log.info(text, *args)
        else:
            self.unsaid += 1

    def swept(self, now: float) -> None:
        """Drop replies older than ``timeout``; log what was dropped since the last sweep, and
        how many lines about single replies were not written."""
        if self.unsaid:
            log.info(
                "two-port: %d more line(s) about dropped or uncollected replies since the last "
                "count, not written (at most %d a second: LOGGED_LINES)",
                self.unsaid,
                LOGGED_LINES,
            )
        self.said = self.unsaid = 0
        kept = deque(
            p for p in self.pending if not p.future.done() or now - p.arrived < self.timeout
        )
        dropped = self.dropped + len(self.pending) - len(kept)
        self.pending, self.dropped = kept, 0
        if dropped:
            log.warning(
                "two-port: dropped %d repl%s nobody collected (kept %g s, at most %d); replies "
                "pair with reply connections by order only",
                dropped,
                "y" if dropped == 1 else "ies",
                self.timeout,
                MAX_UNCLAIMED,
            )


class _MessageConnection(_Connection):
    """Two-port ``port_rx``: collect the message until the client closes, then submit it."""

    def __init__(self, server: TwoPortServer, conn: socket.socket, client: str) -> None:
        super().__init__(server, conn, client)
        self.two_port = server
        self.data = bytearray()

    def opened(self) -> None:
        """Listed, so that a reply connection accepted after it takes what it sent first."""
        self.two_port.receiving[self] = None

    def received(self, chunk: bytes) -> None:
        """Collect; at the end (or past the size limit) submit the message and close."""
        self.data += chunk
        if chunk and len(self.data) <= MAX_MESSAGE_BYTES:
            return
        self.end()

    def take_queued(self) -> None:
        """A reply connection came: read everything the kernel holds; if the client has sent
        something and not closed yet, its message is what it sent (it is reading its reply,
        so it has said what it will say before it)."""
        while not self.closed and self.read():
            pass
        if not self.closed and self.data:
            self.end()

    def end(self) -> None:
        """Submit the message received (if any) and close."""
        two_port = self.two_port
        data = bytes(self.data)
        if data and two_port.link_model is not None:  # over the link model: what reaches the robot
            got = two_port.link_model.inbound(data)
            if got:
                decoded = replace(two_port.codec.decode(got), size=len(data))
                two_port.arrived(decoded, self.order, self.client)
            else:
                log.debug("%s: the link lost the whole message", self.client)
                if two_port.clock is not None:
                    two_port.clock.took(len(data))
                    two_port.bus.interrupt()
        elif data:
            decoded = replace(two_port.codec.decode(data), size=len(data))
            two_port.arrived(decoded, self.order, self.client)
        else:
            log.debug("%s connected and sent nothing: no message", self.client)
        self.close()

    def close(self) -> None:
        """Close and no longer be listed."""
        if self.closed:
            return
        super().close()
        self.two_port.receiving.pop(self, None)


class _ReplyConnection(_Connection):
    """Two-port ``port_tx``: collect the replies waiting (see :class:`TwoPortServer`), send
    them, close."""

    def __init__(self, server: TwoPortServer, conn: socket.socket, client: str) -> None:
        super().__init__(server, conn, client)
        self.two_port = server
        self.collected: list[_Pending] = []

    def opened(self) -> None:
        """Queue up for the replies waiting."""
        self.two_port.waiting.append(self)
        self.two_port.collect()

    def deliver(self, collected: list[_Pending]) -> None:
        """Send ``collected`` as one packet and close (at once if there is nothing to send)."""
        self.collected = collected
        answered = [r for p in collected if (r := p.replies()) is not None]
        data = self.two_port.codec.encode_many(answered)
        self.close_when_sent = True
        if data and self.two_port.link_model is not None:
            self.two_port.link_model.outbound(data, self.arrived)
        else:
            self.arrived(data)

    def arrived(self, data: bytes) -> None:
        """Send what reached the program's end of the link and close (at once if nothing
        did)."""
        if self.closed:
            return
        if data:
            self.send(data)
        else:
            self.close()

    def received(self, chunk: bytes) -> None:
        """Stray bytes are ignored; end of stream means the client left."""
        if not chunk:
            self.close()

    def close(self) -> None:
        """Close; replies not sent go back, in order, for the next reply connection."""
        if self.closed:
            return
        unsent = self.collected and not (self.close_when_sent and not self.outbox)
        super().close()
        two_port = self.two_port
        if self in two_port.waiting:
            two_port.waiting.remove(self)
        if unsent and not self.server.bus.closed:
            two_port.say("%s left before its reply was sent; kept for the next one", self.client)
            two_port.pending = deque(
                sorted([*self.collected, *two_port.pending], key=lambda p: p.order)
            )
            two_port.collect()


class StreamServer(_Server):
    """The persistent protocol: many ``\\n``-terminated messages on one connection, each
    answered in order with a frame (width byte, uint16 count, packed values); a ``?`` line is
    answered with a text frame giving why the last message's NaN replies are NaN."""

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
        idle_timeout: float = 3600.0,
        lenient: bool = False,
        clock: ByteCounter | None = None,
        link_model: Link | None = None,
        listeners: list[socket.socket] | None = None,
    ) -> None:
        super().__init__(bus, host, [port], timeout, idle_timeout, clock, listeners)
        self.link_model = link_model
        """The link model its command messages and their replies cross (None: off)."""
        self.port = self.ports[0]
        self.width = width
        self.encoding = encoding
        self.lenient = lenient
        """Parse commands the original SimMeR's way (a run of an original ``config.py``)."""
        self.remembered: dict[bytes, Decoded] = {}

    def decode(self, line: bytes) -> Decoded:
        """Decode a line (without its ``\\n``) and parse its commands; the decodings of the
        last :data:`REMEMBERED` short lines are kept, as a program sends the same few
        messages again and again (a :class:`Decoded` is immutable)."""
        decoded = self.remembered.get(line)
        if decoded is None:
            clock = line.startswith(CLOCK_PREFIX)
            size = len(line) + 1
            decoded = decode_message(
                line, self.encoding, size=size, clock=clock, lenient=self.lenient
            )
            if size <= REMEMBERED_BYTES:
                if len(self.remembered) >= REMEMBERED:
                    self.remembered.clear()
                self.remembered[line] = decoded
        return decoded

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
    """One persistent-protocol connection: lines in, frames out, in order.

    Lines are taken from the inbox only while fewer than :data:`MAX_IN_FLIGHT` commands wait
    for the loop and no reply waits to be sent; otherwise the socket is not read either, so a
    client that never reads its replies holds a bounded amount and delays nobody."""

    def __init__(self, server: StreamServer, conn: socket.socket, client: str) -> None:
        super().__init__(server, conn, client)
        self.stream = server
        self.inbox = bytearray()
        self.searched = 0
        self.ended = False  # a message over a limit: no more input; close after its reply
        self.last: Reply[list[float]] | None = None
        self.owed: deque[Request | None] = deque()
        """The messages not yet answered on the wire, in the order they came (None: a ``?``):
        frames go out from the front only, so a clock message answered later holds back
        the frames of the messages after it."""
        self.in_flight = 0  # commands (and ``?``) submitted and not yet answered
        self.messages = 0
        self.waiting_for = "owed"  # what the deadline is for: a whole message, or the next one
        self.reasons: list[str] = []  # why the last answered message's NaN replies are NaN
        self.pumping = False  # in :meth:`pump` (a reply sent meanwhile leaves the lines to it)
        self.wire = Wire(server.link_model, self.send)

    def reading(self) -> bool:
        """Read while the connection may have more in flight."""
        return not self.ended and self.in_flight < MAX_IN_FLIGHT

    def received(self, chunk: bytes) -> None:
        """Take in what arrived (end of stream: the client left)."""
        if not chunk:
            self.close()
            return
        if self.ended:
            return
        self.inbox += chunk
        self.pump()

    def drained(self) -> None:
        """Every reply is sent: take the next lines (if any came meanwhile; a reply sent
        while :meth:`pump` runs leaves them to its loop)."""
        if self.pumping:
            return
        if self.inbox:
            self.pump()
        else:
            self.rearm()

    def pump(self) -> None:
        """Submit complete lines while allowed (see the class doc); a line over the size
        limit gets one NaN and ends the connection. The first line may be answered at once
        (:meth:`submit`); the rest wait for the loop's next turn, as other clients' do."""
        inbox = self.inbox
        now = True  # the first line only: one client cannot keep the loop to itself
        self.pumping = True
        while not (self.closed or self.ended or self.outbox) and self.in_flight < MAX_IN_FLIGHT:
            end = inbox.find(b"\n", self.searched)
            if end < 0:
                self.searched = len(inbox)
                if len(inbox) > MAX_MESSAGE_BYTES:
                    reason = f"line longer than {MAX_MESSAGE_BYTES} bytes; closing the connection"
                    self.submit(Refused(reason, over_limit=True, size=len(inbox)), now)
                    inbox.clear()
                break
            line = bytes(inbox[:end])
            del inbox[: end + 1]
            self.searched = 0
            self.messages += 1
            if line in (EXPLAIN, EXPLAIN + b"\r"):
                if self.stream.clock is not None:
                    self.stream.clock.took(end + 1)
                self.explain_later()
            elif line.startswith(META_PREFIX):
                self.submit(decode_meta(line, end + 1), now)
            elif self.stream.link_model is not None and not line.startswith(CLOCK_PREFIX):
                self.submit_linked(self.stream.link_model, line)
            else:
                self.submit(self.stream.decode(line), now)
            now = False
        self.pumping = False
        self.rearm()
        self.update_events()

    def submit_linked(self, link: Link, line: bytes) -> None:
        """A command line over the link model: what reaches the robot is answered (a line
        whose end was lost still ends, as the sketch's silence ends it), its bytes counted
        as the program wrote them; nothing, if every byte was lost (then they count as taken
        at once: a clock message's `` @N`` waits for no message that will never come)."""
        stream = self.stream
        size = len(line) + 1
        got = link.inbound(line + b"\n").rstrip(b"\n")
        if got:
            self.submit(decode_message(got, stream.encoding, size=size, lenient=stream.lenient))
        elif stream.clock is not None:
            stream.clock.took(size)
            stream.bus.interrupt()

    def rearm(self) -> None:
        """Set the deadline while the client owes us something: ``timeout`` before its first
        message or with part of a line received, ``idle_timeout`` between messages; none
        while it waits for us."""
        if self.closed:
            return
        if self.ended or self.in_flight or self.outbox:
            self.deadline = None
            return
        owed = not self.messages or bool(self.inbox)
        kind = "owed" if owed else "idle"
        if self.deadline is None or kind != self.waiting_for:
            limit = self.server.timeout if owed else self.server.idle_timeout
            self.deadline = None if limit is None else time.monotonic() + limit
        self.waiting_for = kind

    def submit(self, decoded: Decoded, now: bool = False) -> None:
        """Queue one message; its frame is sent once the loop has answered it and every
        message before it. With ``now`` the loop may answer it before this returns
        (:meth:`CommandBus.request`)."""
        if decoded.over_limit:
            self.ended = True
        self.in_flight += decoded.count
        request = self.server.bus.request(decoded, self.client, now=now)
        if self.ended:
            self.last = request.future
        if request.future.done() and not self.owed:  # answered at once, nothing before it
            self.reply(request)
            return
        self.owed.append(request)
        if request.future.done():
            self.send_answered()
        else:
            request.future.add_done_callback(lambda _future: self.guard(self.send_answered))

    def send_answered(self) -> None:
        """Send the frames of the answered messages at the front of :attr:`owed`."""
        owed = self.owed
        while owed and (owed[0] is None or owed[0].future.done()):
            request = owed.popleft()
            if request is None:
                self.explain()
            else:
                self.reply(request)

    def reply(self, request: Request) -> None:
        """Loop thread (or a closing bus): send the reply frame of an answered message. A
        frame is checked before it goes: more values than a message may have (none should)
        become one NaN and the end of the connection."""
        self.in_flight -= request.decoded.count
        if self.closed:
            return
        future = request.future
        if future.exception() is not None:
            self.close()
            return
        values = future.result()
        if len(values) > MAX_COMMANDS:
            log.error(
                "%s: %d replies to one message; sending NaN, closing", self.client, len(values)
            )
            values, self.ended, self.last = [math.nan], True, future
        self.reasons = request.reasons
        self.close_when_sent = future is self.last
        if request.answer:  # a localization message's text (``%maze``)
            self.wire.direct(frame_document(request.answer[0]))
            return
        match request.decoded:
            case ClockText() | Refused(clock=True):  # a time needs float64
                self.wire.direct(frame_replies(values, 8))
            case LocalizationText():
                self.wire.direct(frame_replies(values, self.stream.width))
            case CommandText() | Refused():  # what the robot answers: over the link
                self.wire.reply(frame_replies(values, self.stream.width))

    def explain_later(self) -> None:
        """Answer ``?`` once the messages before it are answered (frames go out in order)."""
        self.in_flight += 1
        self.owed.append(None)
        self.send_answered()

    def explain(self) -> None:
        """Send the reasons of the last answered message as a text frame."""
        self.in_flight -= 1
        if not self.closed:
            self.wire.direct(frame_text("\n".join(self.reasons)))
