"""A virtual serial port: a pseudo-terminal that speaks what the Arduino robot speaks.

A program opens the printed path (or the stable link) with pyserial as if it were the robot's
Bluetooth port. With packed replies (SimMeR v1.0/v1.1, the Arduino examples) a command ends at
``\\n`` or after 50 ms of silence, like the Arduino sketch, and each reply is the packed floats,
one per command, with no framing. With SimMeR v1.2's framed text a message ends at the frame's
closing character, as the v1.2 Arduino example reads it; text outside frames is ignored and the
reply is one frame (``[u0:15.45]``) with no line ending, so a program reads until ``]``.

The port is served by the loop thread, as the TCP transports are: the bus watches the
pseudo-terminal, the 50 ms silence is a timer on the bus, and a reply is written when its
message has been answered; no thread waits for a reply. Replies go out in the order the
messages came. A failure answering one message (no reply within ``timeout``, a codec that
raises) is logged and the port goes on serving; while a program does not read its replies,
nothing more is read from it (the pseudo-terminal holds what it writes). The stable link is
made only where nothing is, and removed only while it is still the one made here.
"""

from __future__ import annotations

import contextlib
import io
import logging
import os
import selectors
import threading
import tty
from collections import deque
from dataclasses import replace
from pathlib import Path

from simmer.errors import BusClosed, SimmerError
from simmer.protocol import (
    MAX_MESSAGE_BYTES,
    Decoded,
    FramedCodec,
    PackedCodec,
    Refused,
    ReplyCodec,
)
from simmer.transport.bus import ByteCounter, CommandBus, Reply, Timer
from simmer.transport.link import Link, Wire

log = logging.getLogger("simmer.transport")

SILENCE = 0.05
"""Seconds of silence that end a command without a newline (the Arduino sketch's rule)."""


class _Owed:
    """A message whose reply is still to be written, and its ``timeout`` timer."""

    __slots__ = ("decoded", "future", "timer")

    def __init__(self, decoded: Decoded, future: Reply[list[float]]) -> None:
        self.decoded = decoded
        self.future = future
        self.timer: Timer | None = None


class SerialServer:
    """Serve the bus over a pseudo-terminal; ``path`` is the device to open, ``link`` the
    optional stable symlink to it, ``silence`` the seconds of quiet that end a packed command
    (the Arduino's 50 ms; a test sets it long or short to make a pause certain), ``clock``
    where the bytes it sets aside are counted (None: nowhere, a port off any run's clock)."""

    kind = "serial"

    def __init__(
        self,
        bus: CommandBus,
        link: str | Path | None = None,
        *,
        codec: ReplyCodec | None = None,
        timeout: float = 300.0,
        silence: float = SILENCE,
        clock: ByteCounter | None = None,
        link_model: Link | None = None,
    ) -> None:
        self.bus = bus
        self.clock = clock
        self.link_model = link_model
        """The link model its messages and replies cross (None: off)."""
        self.silence = silence
        self.received = 0
        """Bytes read from the port so far (what a test waits on)."""
        self.codec: ReplyCodec = codec if codec is not None else PackedCodec()
        codec = self.codec
        self._frame: tuple[bytes, bytes] | None = None
        if isinstance(codec, FramedCodec):
            self._frame = (codec.start.encode(), codec.end.encode())
        self.timeout = timeout
        self._master, self._slave = os.openpty()
        tty.setraw(self._slave)  # no echo, no newline translation: replies are binary
        os.set_blocking(self._master, False)
        self.path = os.ttyname(self._slave)
        self.link = Path(link) if link is not None else None
        self.client = f"serial {self.path}"
        self._port = io.FileIO(self._master, "r+", closefd=False)
        """The master side as something the bus's selector can watch."""
        self._buffer = bytearray()
        self._outbox = bytearray()
        self._wire = Wire(link_model, self._write)
        self._owed: deque[_Owed] = deque()
        self._quiet: Timer | None = None
        self._serving = threading.RLock()
        """Held while a callback or :meth:`close` uses the port (a reply may complete in
        the thread closing the bus)."""
        self._stopping = threading.Event()
        self._events = 0
        self._failures = 0
        if self.link is not None:
            try:
                self._make_link(self.link)
            except BaseException:
                self._close_fds()
                raise

    def _make_link(self, link: Path) -> None:
        """Make ``link`` point at the port; refuse if anything is there already (the
        simulator never replaces, nor later deletes, what it did not create)."""
        try:
            link.symlink_to(self.path)  # atomic: fails if the path exists, even dangling
        except FileExistsError:
            if link.is_symlink():
                what = f"a link to {os.readlink(link)}"
            else:
                what = "a directory" if link.is_dir() else "a file"
            raise SimmerError(
                f"cannot make the serial link {link}: {what} is already there, and simmer does "
                "not replace what it did not create. Remove it (a simmer that was killed may "
                "have left it) or choose another path."
            ) from None

    def _owns_link(self) -> bool:
        """Whether the link is still the one made here (not replaced meanwhile)."""
        if self.link is None:
            return False
        try:
            return os.readlink(self.link) == self.path
        except OSError:
            return False

    def start(self) -> None:
        """Start serving (the loop must be running to serve it)."""
        self.bus.connect(self.client, self.kind)
        self._update()

    def _update(self) -> None:
        """Watch for what the port needs now: writability while a reply waits to be written,
        readability once every message read has been answered (one message at a time, as the
        Arduino is driven, and a program that does not read its replies holds nothing more),
        else nothing."""
        if self._outbox:
            events = selectors.EVENT_WRITE
        else:
            events = 0 if self._owed else selectors.EVENT_READ
        if events == self._events or self._stopping.is_set():
            return
        self._events = events
        with contextlib.suppress(BusClosed):  # the simulation has stopped: nothing to do
            if events:
                self.bus.watch(self._port, self._ready, events, self._failed)
            else:
                self.bus.unwatch(self._port)

    def _failed(self, exc: Exception) -> None:
        if not self._stopping.is_set():
            log.error("serial port %s stopped: %s", self.path, exc)

    def _ready(self, events: int) -> bool:
        """Loop thread: write what waits, or read what came and answer what it completes."""
        with self._serving:
            if self._stopping.is_set():
                return False
            if events & selectors.EVENT_WRITE:
                self._flush()
            elif events & selectors.EVENT_READ:
                self._read()
            self._update()
            return True

    def _read(self) -> None:
        try:
            chunk = os.read(self._master, 65536)
        except BlockingIOError:
            return
        buffer = self._buffer
        buffer += chunk
        self._split(buffer)
        if len(buffer) > MAX_MESSAGE_BYTES:
            self._answer(bytes(buffer), len(buffer))
            buffer.clear()
        if buffer and self._frame is None:  # framed messages end at the frame's end only
            if self._quiet is not None:
                self._quiet.cancel()
            self._quiet = self.bus.call_later(self.silence, self._silent)
        self.received += len(chunk)  # counted once handled: a test waits on it

    def _silent(self) -> None:
        """Loop thread: the silence that ends a command without a newline has passed."""
        with self._serving:
            self._quiet = None
            if self._buffer and not self._stopping.is_set():
                self._answer(bytes(self._buffer), len(self._buffer))
                self._buffer.clear()
                self._update()

    def _split(self, buffer: bytearray) -> None:
        """Answer every complete message at the front of ``buffer`` and remove it."""
        if self._frame is None:
            while (end := buffer.find(b"\n")) >= 0:
                line = bytes(buffer[:end])
                del buffer[: end + 1]
                self._answer(line, end + 1)
            return
        start, stop = self._frame
        while (end := buffer.find(stop)) >= 0:
            message = bytes(buffer[: end + len(stop)])
            del buffer[: end + len(stop)]
            self._answer(message, len(message))
        if start not in buffer:
            self._set_aside(len(buffer))
            buffer.clear()  # text outside frames (line endings, say) is ignored

    def _set_aside(self, size: int) -> None:
        """Count ``size`` bytes read and not answered as taken, and wake the loop: it may be
        waiting for the count (a clock message's `` @N``)."""
        if self.clock is not None and size > 0:
            self.clock.took(size)
            self.bus.interrupt()

    def _answer(self, data: bytes, size: int) -> None:
        """Ask for one message, read from ``size`` bytes of the port, to be answered; its
        reply is written once it and every message before it are answered. A failure is
        logged (the first in full) and serving goes on."""
        if self.link_model is not None:  # what reaches the robot over the link model
            ending = b"\n" * (size - len(data))  # the line's end costs the wire time too
            data = self.link_model.inbound(data + ending).rstrip(b"\n")
            if not data:  # lost whole: no message will take its bytes
                self._set_aside(size)
                return
        try:
            decoded = replace(self.codec.decode(data), size=size)
        except Exception as exc:
            self._failure(exc)
            return
        if isinstance(decoded, Refused) and decoded.count == 0:  # nothing to send back
            log.warning("%s: %s", self.client, decoded.error)
            self._set_aside(size)
            return
        owed = _Owed(decoded, self.bus.request(decoded, self.client, now=True).future)
        self._owed.append(owed)
        if not owed.future.done():
            owed.timer = self.bus.call_later(self.timeout, lambda: self._expire(owed))
            owed.future.add_done_callback(lambda _future: self._send_answered())
        self._send_answered()

    def _expire(self, owed: _Owed) -> None:
        """Loop thread: no reply within ``timeout``; drop the message, send what follows."""
        with self._serving:
            if owed in self._owed and not owed.future.done():
                self._owed.remove(owed)
                log.warning(
                    "%s: no reply within %g s; the message is dropped", self.client, self.timeout
                )
                self._send_answered()

    def _send_answered(self) -> None:
        """Write the replies of the answered messages at the front, in order."""
        with self._serving:
            while self._owed and self._owed[0].future.done() and not self._stopping.is_set():
                owed = self._owed.popleft()
                if owed.timer is not None:
                    owed.timer.cancel()
                if owed.future.exception() is not None:
                    continue  # the simulation stopped
                try:
                    reply = self.codec.encode(owed.decoded, owed.future.result())
                except Exception as exc:
                    self._failure(exc)
                else:
                    self._wire.reply(reply)
            self._update()

    def _write(self, data: bytes) -> None:
        """Write ``data`` after what waits (a reply that reached the program's end)."""
        with self._serving:
            if self._stopping.is_set():
                return
            self._outbox += data
            if self._outbox:
                self._flush()
            self._update()

    def _failure(self, exc: Exception) -> None:
        """Count a message that could not be answered; log the first in full."""
        self._failures += 1
        if self._failures == 1:
            log.error(
                "%s: answering a message failed; the port goes on serving (more failures "
                "are counted, not logged): %s",
                self.client,
                exc,
                exc_info=exc,
            )

    def _flush(self) -> None:
        """Write as much of the waiting replies as the pseudo-terminal takes now."""
        try:
            written = os.write(self._master, self._outbox)
        except BlockingIOError:
            return
        del self._outbox[:written]
        if self.clock is not None:
            self.clock.gave(written)

    def close(self) -> None:
        """Stop serving, remove the link and close the pseudo-terminal."""
        if self._stopping.is_set():
            return
        self._stopping.set()
        self.bus.unwatch(self._port)
        with self._serving:
            if self._quiet is not None:
                self._quiet.cancel()
            for owed in self._owed:
                if owed.timer is not None:
                    owed.timer.cancel()
        self.bus.disconnect(self.client)
        if self._failures > 1:
            log.error("%s: %d messages could not be answered", self.client, self._failures)
        if self.link is not None and self._owns_link():
            self.link.unlink()
        self._close_fds()

    def _close_fds(self) -> None:
        self._port.close()
        for fd in (self._master, self._slave):
            os.close(fd)

    def __enter__(self) -> SerialServer:
        self.start()
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()
