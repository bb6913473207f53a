"""A virtual serial port: a pseudo-terminal that speaks what the Arduino robot speaks.

A program opens the printed path (or the stable link) with pyserial as if it were the robot's
Bluetooth port. A command ends at ``\\n`` or after 50 ms of silence, like the Arduino sketch;
each reply is the packed floats, one per command, with no framing.
"""

from __future__ import annotations

import logging
import os
import select
import threading
import time
import tty
from pathlib import Path

from simmer.protocol import MAX_MESSAGE_BYTES, decode_message, pack_replies
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
        width: int = 4,
        encoding: str = "utf-8",
        timeout: float = 300.0,
    ) -> None:
        self.bus = bus
        self.width = width
        self.encoding = encoding
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
        try:
            while True:
                wait = None if not buffer else max(0.0, last + SILENCE - time.monotonic())
                readable, _, _ = select.select([self._master, self._wake_r], [], [], wait)
                if self._wake_r in readable:
                    return
                if not readable:  # 50 ms of silence: what we have is a command
                    self._answer(bytes(buffer))
                    buffer.clear()
                    continue
                buffer += os.read(self._master, 65536)
                last = time.monotonic()
                while (end := buffer.find(b"\n")) >= 0:
                    line = bytes(buffer[:end])
                    del buffer[: end + 1]
                    self._answer(line)
                if len(buffer) > MAX_MESSAGE_BYTES:
                    self._answer(bytes(buffer))
                    buffer.clear()
        except (BusClosed, OSError) as exc:
            if not self._stopping.is_set():
                log.error("serial port %s stopped: %s", self.path, exc)

    def _answer(self, data: bytes) -> None:
        decoded = decode_message(data, self.encoding)
        replies = self.bus.submit(decoded, self.client).result(timeout=self.timeout)
        reply = memoryview(pack_replies(replies, self.width))
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
