"""A virtual RPLidar: a pseudo-terminal that speaks Slamtec's serial protocol for a LiDAR.

A program written for the real scanner (``RPLidar(port).iter_scans()`` of the ``rplidar``
package, or Slamtec's SDK) reads the simulator's LiDAR by changing only the port name. What it
answers (Slamtec's protocol document, as the ``rplidar`` package reads it):

* a request is ``A5 cmd``; a command from ``0x80`` on has a size byte, a payload and an XOR
  checksum;
* ``GET_INFO`` (50): a 7-byte descriptor ``A5 5A 14 00 00 00 04`` then 20 bytes: model
  (``0x18``, an A1M8), firmware 1.29, hardware 7, a 16-byte serial number;
* ``GET_HEALTH`` (52): descriptor ``A5 5A 03 00 00 00 06``, then ``00 00 00`` (good);
* ``GET_SAMPLERATE`` (59): descriptor ``A5 5A 04 00 00 00 15``, then the microseconds per
  sample (standard and express) as two little-endian uint16;
* ``SCAN`` (20) and ``FORCE_SCAN`` (21): descriptor ``A5 5A 05 00 00 40 81``, then every
  whole scan the LiDAR makes from then on as 5-byte measurement nodes: quality << 2 with the
  start flag S and its inverse in bits 0-1 (S on a scan's first node), the angle in 1/64
  degree shifted left one with the check bit 1, the distance in 1/4 mm (0 and quality 0: no
  return). Angles are the beams' nominal ones, clockwise from the LiDAR's front;
* ``STOP`` (25) and ``RESET`` (40): the stream stops; ``SET_PWM`` (F0, payload uint16): 0 stops
  the motor, so no scans come until it is set again; ``EXPRESS_SCAN`` (82) is not served (a
  warning says so, once).

The motor line (DTR) a program sets to start the A1M8's motor cannot be carried by a
pseudo-terminal: Linux and macOS refuse the modem-control ioctl on one (``OSError: [Errno 25]
Inappropriate ioctl for device`` from pyserial's ``setDTR``). A program started by ``simmer run
--program`` needs no change (the lockstep shim answers those ioctls on this port); one started
by hand adds one line (docs/devices.md).

The scans come from an observer of the run's steps, called in the loop thread that owns the
simulation: it reads the LiDAR's latest scan there and never commands anything. What the
program does not read waits in the pseudo-terminal and here, up to :data:`MAX_BACKLOG` bytes;
beyond it the oldest whole scans are dropped, as a real scanner's serial link overruns.
"""

from __future__ import annotations

import contextlib
import io
import logging
import os
import selectors
import struct
import threading
import tty
from collections import deque
from pathlib import Path

import numpy as np

from simmer.errors import BusClosed, SimmerError
from simmer.transport.bus import ByteCounter, CommandBus

log = logging.getLogger("simmer.transport")

SYNC = 0xA5
DESCRIPTOR = b"\xa5\x5a"
STOP, RESET, SCAN, FORCE_SCAN = 0x25, 0x40, 0x20, 0x21
GET_INFO, GET_HEALTH, GET_SAMPLERATE = 0x50, 0x52, 0x59
EXPRESS_SCAN, SET_PWM = 0x82, 0xF0
MODEL_A1M8 = 0x18
FIRMWARE = (1, 29)
HARDWARE = 7
QUALITY = 15
"""The quality a return reports (the A1M8's usual value for a wall)."""
MM_PER_INCH = 25.4
MAX_BACKLOG = 64 * 1024
"""Bytes of scans kept for a program that does not read (a real link overruns instead)."""


def descriptor(size: int, multiple: bool, kind: int) -> bytes:
    """A response descriptor: sync, 30-bit length and 2-bit mode, data type."""
    return DESCRIPTOR + struct.pack("<IB", size | ((1 if multiple else 0) << 30), kind)


def nodes(angles: np.ndarray, distances_in: np.ndarray) -> bytes:
    """A whole scan as 5-byte measurement nodes (the module doc's format)."""
    n = len(angles)
    out = np.zeros((n, 5), dtype=np.uint8)
    q6 = np.round(np.asarray(angles) * 64.0).astype(np.int64) % (360 * 64)
    q2 = np.round(np.asarray(distances_in) * MM_PER_INCH * 4.0).astype(np.int64)
    q2 = np.clip(q2, 0, 0xFFFF)
    quality = np.where(q2 > 0, QUALITY, 0)
    start = np.zeros(n, dtype=np.int64)
    start[0] = 1
    out[:, 0] = (quality << 2) | ((1 - start) << 1) | start
    out[:, 1] = ((q6 & 0x7F) << 1) | 1
    out[:, 2] = q6 >> 7
    out[:, 3] = q2 & 0xFF
    out[:, 4] = q2 >> 8
    return out.tobytes()


class RPLidarServer:
    """Serve LiDAR ``device`` on a pseudo-terminal (``path``; ``link``: an optional stable
    link to it) in Slamtec's protocol (module doc); ``clock`` counts the bytes it reads and
    writes, as the serial port's are."""

    kind = "rplidar"

    def __init__(
        self,
        bus: CommandBus,
        device: str,
        link: str | Path | None = None,
        *,
        clock: ByteCounter | None = None,
    ) -> None:
        self.bus = bus
        self.device = device
        self.clock = clock
        self._master, self._slave = os.openpty()
        tty.setraw(self._slave)
        os.set_blocking(self._master, False)
        self.path = os.ttyname(self._slave)
        self.link = Path(link) if link is not None else None
        self.client = f"rplidar {self.path}"
        self._port = io.FileIO(self._master, "r+", closefd=False)
        self._buffer = bytearray()
        self._outbox: deque[bytes] = deque()
        """Whole responses and scans waiting to be written, oldest first."""
        self._queued = 0
        self._partial = 0
        """Bytes of the front of the outbox already written."""
        self.scanning = False
        self.motor = True
        self.sent_scans = 0
        self._last = 0
        """The number of the last scan seen (streamed or not)."""
        self._express_warned = False
        self._overrun = False
        self._events = -1
        self._serving = threading.RLock()
        self._stopping = threading.Event()
        if self.link is not None:
            try:
                self.link.symlink_to(self.path)
            except FileExistsError:
                self._close_fds()
                raise SimmerError(
                    f"cannot make the LiDAR's serial link {self.link}: something is already "
                    "there, and simmer does not replace what it did not create; remove it or "
                    "choose another path"
                ) from None

    # -- the loop thread's side ----------------------------------------------------------

    def start(self) -> None:
        """Start serving (the loop must be running to serve it)."""
        self.bus.connect(self.client, self.kind)
        self._update()

    def _update(self) -> None:
        events = selectors.EVENT_READ | (selectors.EVENT_WRITE if self._outbox else 0)
        if events == self._events or self._stopping.is_set():
            return
        self._events = events
        with contextlib.suppress(BusClosed):
            self.bus.watch(self._port, self._ready, events, self._failed)

    def _failed(self, exc: Exception) -> None:
        if not self._stopping.is_set():
            log.error("virtual RPLidar %s stopped: %s", self.path, exc)

    def _ready(self, events: int) -> bool:
        with self._serving:
            if self._stopping.is_set():
                return False
            if events & selectors.EVENT_READ:
                self._read()
            if self._outbox:
                self._flush()
            self._update()
            return True

    def _read(self) -> None:
        try:
            chunk = os.read(self._master, 4096)
        except BlockingIOError:
            return
        if self.clock is not None and chunk:
            self.clock.took(len(chunk))
            self.bus.interrupt()
        self._buffer += chunk
        self._requests()

    def _requests(self) -> None:
        """Answer every complete request at the front of the buffer (bytes before a sync
        byte are dropped, as the scanner's firmware skips them)."""
        buffer = self._buffer
        while True:
            start = buffer.find(SYNC)
            if start < 0:
                buffer.clear()
                return
            del buffer[:start]
            if len(buffer) < 2:
                return
            command = buffer[1]
            if command < 0x80:
                del buffer[:2]
                self._command(command, b"")
                continue
            if len(buffer) < 3 or len(buffer) < 4 + buffer[2]:
                return
            size = buffer[2]
            payload, checksum = bytes(buffer[3 : 3 + size]), buffer[3 + size]
            whole = bytes(buffer[: 3 + size])
            del buffer[: 4 + size]
            check = 0
            for byte in whole:
                check ^= byte
            if check != checksum:
                log.warning("%s: request %02X with a wrong checksum; ignored", self.client, command)
                continue
            self._command(command, payload)

    def _command(self, command: int, payload: bytes) -> None:
        if command in (STOP, RESET):
            self.scanning = False
            self._outbox.clear()
            self._queued = self._partial = 0
        elif command == GET_INFO:
            serial = bytes(range(16))
            body = struct.pack("<BBBB", MODEL_A1M8, FIRMWARE[1], FIRMWARE[0], HARDWARE) + serial
            self._queue(descriptor(20, False, 4) + body)
        elif command == GET_HEALTH:
            self._queue(descriptor(3, False, 6) + b"\x00\x00\x00")
        elif command == GET_SAMPLERATE:
            self._queue(descriptor(4, False, 0x15) + struct.pack("<HH", 500, 125))
        elif command in (SCAN, FORCE_SCAN):
            self._queue(descriptor(5, True, 0x81))
            self.scanning = True
        elif command == SET_PWM and len(payload) == 2:
            self.motor = struct.unpack("<H", payload)[0] > 0
        elif command == EXPRESS_SCAN and not self._express_warned:
            self._express_warned = True
            log.warning(
                "%s: EXPRESS_SCAN is not served by the virtual RPLidar; use SCAN (what "
                "iter_scans() sends)",
                self.client,
            )

    def _queue(self, data: bytes) -> None:
        self._outbox.append(data)
        self._queued += len(data)
        while self._queued > MAX_BACKLOG and len(self._outbox) > 1:
            oldest = 1 if self._partial else 0  # what is half written goes out whole
            self._queued -= len(self._outbox[oldest])
            del self._outbox[oldest]
            if not self._overrun:
                self._overrun = True
                log.warning(
                    "%s: the program is not reading the scans; past %d KiB (MAX_BACKLOG) the "
                    "oldest are dropped, as a real scanner's link overruns",
                    self.client,
                    MAX_BACKLOG // 1024,
                )

    def _flush(self) -> None:
        while self._outbox:
            front = self._outbox[0]
            try:
                written = os.write(self._master, front[self._partial :])
            except BlockingIOError:
                return
            if self.clock is not None:
                self.clock.gave(written)
            self._partial += written
            if self._partial < len(front):
                return
            self._outbox.popleft()
            self._queued -= len(front)
            self._partial = 0

    def scan(self, number: int, angles: np.ndarray, distances: np.ndarray) -> None:
        """Loop thread: the LiDAR's latest scan is ``number``; stream it if it is new and the
        scanner is scanning with its motor on."""
        if number == self._last:
            return
        self._last = number
        if not (self.scanning and self.motor) or self._stopping.is_set():
            return
        with self._serving:
            self._queue(nodes(angles, distances))
            self.sent_scans += 1
            self._flush()
            self._update()

    # -- the end -------------------------------------------------------------------------

    def close(self) -> None:
        """Stop serving, remove the link and close the pseudo-terminal."""
        if self._stopping.is_set():
            return
        self._stopping.set()
        with contextlib.suppress(BusClosed):
            self.bus.unwatch(self._port)
        self.bus.disconnect(self.client)
        if self.link is not None and self.link.is_symlink():
            with contextlib.suppress(OSError):
                if os.readlink(self.link) == self.path:
                    self.link.unlink()
        self._close_fds()

    def _close_fds(self) -> None:
        self._port.close()
        for fd in (self._master, self._slave):
            os.close(fd)

    def __enter__(self) -> RPLidarServer:
        self.start()
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()
