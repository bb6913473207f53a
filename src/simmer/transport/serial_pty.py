"""A virtual serial port: a pseudo-terminal that speaks what the Arduino robot speaks.

A program opens the printed path (or the stable link) with pyserial as if it were the robot's
Bluetooth port. With packed replies (SimMeR v1.0/v1.1, the Arduino examples) a command ends at
``\\n`` or after 50 ms of silence, like the Arduino sketch, and each reply is the packed floats,
one per command, with no framing. With SimMeR v1.2's framed text a message ends at the frame's
closing character, as the v1.2 Arduino example reads it; text outside frames is ignored and the
reply is one frame (``[u0:15.45]``) with no line ending, so a program reads until ``]``.
"""

from __future__ import annotations

import logging
import os
import select
import threading
import time
import tty
from pathlib import Path

from simmer.protocol import MAX_MESSAGE_BYTES, FramedCodec, PackedCodec, ReplyCodec
from simmer.transport.bus import BusClosed, CommandBus

log = logging.getLogger("simmer.transport")

SILENCE = 0.05
"""Seconds of silence that end a command without a newline (the Arduino sketch's rule)."""


class SerialServer:
    """Serve the bus over a pseudo-terminal; ``path`` is the device to open, ``link`` the
    optional stable symlink to it."""

    kind = "serial"

    def __init__(
        self,
        bus: CommandBus,
        link: str | Path | None = None,
        *,
        codec: ReplyCodec | None = None,
        timeout: float = 300.0,
    ) -> None:
        self.bus = bus
        self.codec: ReplyCodec = codec if codec is not None else PackedCodec()
        codec = self.codec
        self._frame: tuple[bytes, bytes] | None = None
        if isinstance(codec, FramedCodec):
            self._frame = (codec.start.encode(), codec.end.encode())
        self.timeout = timeout
        self._master, self._slave = os.openpty()
        tty.setraw(self._slave)  # no echo, no newline translation: replies are binary
        self.path = os.ttyname(self._slave)
        self.link = Path(link) if link is not None else None
        self.client = f"serial {self.path}"
        self._wake_r, self._wake_w = os.pipe()
        self._stopping = threading.Event()
        self._thread = threading.Thread(target=self._loop, name="simmer-serial", daemon=True)
        if self.link is not None:
            try:
                if self.link.is_symlink():
                    self.link.unlink()
                self.link.symlink_to(self.path)
            except OSError:
                self._close_fds()
                raise

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
                wait = max(0.0, last + SILENCE - time.monotonic()) if waiting else None
                readable, _, _ = select.select([self._master, self._wake_r], [], [], wait)
                if self._wake_r in readable:
                    return
                if not readable:  # 50 ms of silence: what we have is a command
                    self._answer(bytes(buffer))
                    buffer.clear()
                    continue
                buffer += os.read(self._master, 65536)
                last = time.monotonic()
                self._split(buffer)
                if len(buffer) > MAX_MESSAGE_BYTES:
                    self._answer(bytes(buffer))
                    buffer.clear()
        except (BusClosed, OSError) as exc:
            if not self._stopping.is_set():
                log.error("serial port %s stopped: %s", self.path, exc)

    def _split(self, buffer: bytearray) -> None:
        """Answer every complete message at the front of ``buffer`` and remove it."""
        if self._frame is None:
            while (end := buffer.find(b"\n")) >= 0:
                line = bytes(buffer[:end])
                del buffer[: end + 1]
                self._answer(line)
            return
        start, stop = self._frame
        while (end := buffer.find(stop)) >= 0:
            message = bytes(buffer[: end + len(stop)])
            del buffer[: end + len(stop)]
            self._answer(message)
        if start not in buffer:
            buffer.clear()  # text outside frames (line endings, say) is ignored

    def _answer(self, data: bytes) -> None:
        decoded = self.codec.decode(data)
        if decoded.text is None and decoded.count == 0:
            log.warning("%s: %s", self.client, decoded.error)
            return
        replies = self.bus.submit(decoded, self.client).result(timeout=self.timeout)
        reply = memoryview(self.codec.encode(decoded, replies))
        while reply:
            reply = reply[os.write(self._master, reply) :]

    def close(self) -> None:
        """Stop serving, remove the link and close the pseudo-terminal."""
        if self._stopping.is_set():
            return
        self._stopping.set()
        os.write(self._wake_w, b"x")
        if self._thread.is_alive():
            self._thread.join(timeout=2.0)
        self.bus.disconnect(self.client)
        if self.link is not None and self.link.is_symlink():
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
