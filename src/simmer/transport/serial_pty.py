"""A virtual serial port: a pseudo-terminal that speaks what the Arduino robot speaks.

A program opens the printed path (or the stable link) with pyserial as if it were the robot's
Bluetooth port. With packed replies (SimMeR v1.0/v1.1, the Arduino examples) a command ends at
``\\n`` or after 50 ms of silence, like the Arduino sketch, and each reply is the packed floats,
one per command, with no framing. With SimMeR v1.2's framed text a message ends at the frame's
closing character, as the v1.2 Arduino example reads it; text outside frames is ignored and the
reply is one frame (``[u0:15.45]``) with no line ending, so a program reads until ``]``.

A failure answering one message (no reply within ``timeout``, a codec that raises) is logged
and the port goes on serving; a program that does not read its replies holds only this port's
thread, which :meth:`SerialServer.close` still stops. The stable link is made only where nothing
is, and removed only while it is still the one made here.
"""

from __future__ import annotations

import logging
import os
import select
import threading
import time
import tty
from dataclasses import replace
from pathlib import Path

from simmer.errors import BusClosed, SimmerError
from simmer.protocol import MAX_MESSAGE_BYTES, FramedCodec, PackedCodec, Refused, ReplyCodec
from simmer.transport.bus import ByteCounter, CommandBus

log = logging.getLogger("simmer.transport")

SILENCE = 0.05
"""Seconds of silence that end a command without a newline (the Arduino sketch's rule)."""


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
    ) -> None:
        self.bus = bus
        self.clock = clock
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
        self._wake_r, self._wake_w = os.pipe()
        self._stopping = threading.Event()
        self._failures = 0
        self._thread = threading.Thread(target=self._loop, name="simmer-serial", daemon=True)
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
        """Start serving."""
        self.bus.connect(self.client, self.kind)
        self._thread.start()

    def _loop(self) -> None:
        buffer = bytearray()
        last = time.monotonic()
        silence = self._frame is None  # framed messages end at the frame's end, never by time
        try:
            while True:
                waiting = buffer and silence
                wait = max(0.0, last + self.silence - time.monotonic()) if waiting else None
                readable, _, _ = select.select([self._master, self._wake_r], [], [], wait)
                if self._wake_r in readable:
                    return
                if not readable:  # silence: what we have is a command
                    self._answer(bytes(buffer), len(buffer))
                    buffer.clear()
                    continue
                try:
                    chunk = os.read(self._master, 65536)
                except BlockingIOError:
                    continue
                buffer += chunk
                last = time.monotonic()
                self._split(buffer)
                if len(buffer) > MAX_MESSAGE_BYTES:
                    self._answer(bytes(buffer), len(buffer))
                    buffer.clear()
                self.received += len(chunk)  # counted once handled: a test waits on it
        except (BusClosed, OSError) as exc:
            if not self._stopping.is_set():
                log.error("serial port %s stopped: %s", self.path, exc)

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
        """Answer one message, read from ``size`` bytes of the port; a failure is logged (the
        first in full) and serving goes on. Only the port closing or the loop stopping ends
        the thread."""
        try:
            decoded = replace(self.codec.decode(data), size=size)
            if isinstance(decoded, Refused) and decoded.count == 0:  # nothing to send back
                log.warning("%s: %s", self.client, decoded.error)
                self._set_aside(size)
                return
            replies = self.bus.submit(decoded, self.client).result(timeout=self.timeout)
            self._write(self.codec.encode(decoded, replies))
        except TimeoutError:
            log.warning(
                "%s: no reply within %g s; the message is dropped", self.client, self.timeout
            )
        except (BusClosed, OSError):
            raise
        except Exception as exc:
            self._failures += 1
            if self._failures == 1:
                log.error(
                    "%s: answering a message failed; the port goes on serving (more failures "
                    "are counted, not logged): %s",
                    self.client,
                    exc,
                    exc_info=exc,
                )

    def _write(self, data: bytes) -> None:
        """Write all of ``data``, waiting while the pseudo-terminal is full (nobody reads);
        give up if the server is closing."""
        reply = memoryview(data)
        while reply:
            try:
                reply = reply[os.write(self._master, reply) :]
            except BlockingIOError:
                readable, _, _ = select.select([self._wake_r], [self._master], [])
                if self._wake_r in readable:
                    return

    def close(self) -> None:
        """Stop serving, remove the link and close the pseudo-terminal."""
        if self._stopping.is_set():
            return
        self._stopping.set()
        os.write(self._wake_w, b"x")
        if self._thread.is_alive():
            self._thread.join(timeout=2.0)
        self.bus.disconnect(self.client)
        if self._failures > 1:
            log.error("%s: %d messages could not be answered", self.client, self._failures)
        if self.link is not None and self._owns_link():
            self.link.unlink()
        self._close_fds()

    def _close_fds(self) -> None:
        for fd in (self._master, self._slave, self._wake_r, self._wake_w):
            os.close(fd)

    def __enter__(self) -> SerialServer:
        self.start()
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()
