"""``simmer tap``: sit between a program and the robot, forward every byte, record the run.

The tap opens a pseudo-terminal for the program (it opens the printed path, or the stable
``link``, instead of the robot's port) and the robot's own port (a serial device with pyserial,
or ``tcp://HOST:PORT``, any endpoint that speaks a SimMeR protocol as a stream). One thread
waits on both with ``select`` and writes each chunk read from one side to the other at once,
unchanged; then it reads along (:class:`~simmer.tap.decode.TapDecoder`) and records each
exchange in a run folder (:mod:`simmer.tap.folder`): the real run, with wall-clock times and
no true pose.

It ends when the program it started exits (``program``), when ``stop`` is set (Ctrl-C), or
when the robot goes: its port closes or fails. Whatever it recorded until then stays, and
the report says how it ended.
"""

from __future__ import annotations

import contextlib
import os
import selectors
import socket
import subprocess
import threading
import time
import tty
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Protocol

from simmer.config.models import SimConfig
from simmer.errors import TapError
from simmer.tap.decode import SILENCE, Exchange, TapDecoder
from simmer.tap.folder import TapRecorder

CHUNK = 4096
"""Bytes read from one side at a time."""
TCP_PREFIX = "tcp://"


class _Port(Protocol):
    def fileno(self) -> int: ...
    def read(self) -> bytes: ...
    def write(self, data: bytes) -> None: ...
    def close(self) -> None: ...


class _SerialPort:
    """The robot's serial port (pyserial), read without waiting."""

    def __init__(self, path: str, baudrate: int) -> None:
        import serial  # pyserial

        try:
            self.port = serial.Serial(path, baudrate=baudrate, timeout=0)
        except (serial.SerialException, OSError, ValueError) as exc:
            raise TapError(
                f"cannot open the robot's port {path}: {exc}; check its name "
                "(simmer tap --help lists how ports are named) and that nothing else has it open"
            ) from None

    def fileno(self) -> int:
        return int(self.port.fileno())

    def read(self) -> bytes:
        data = bytes(self.port.read(self.port.in_waiting or 1))
        if not data:  # readable, yet nothing: the device went away
            raise OSError("the port closed")
        return data

    def write(self, data: bytes) -> None:
        self.port.write(data)

    def close(self) -> None:
        with contextlib.suppress(Exception):
            self.port.close()


class _TcpPort:
    """A SimMeR endpoint that is a TCP stream (the persistent port)."""

    def __init__(self, address: str) -> None:
        host, _, port = address.rpartition(":")
        if not host or not port.isdigit():
            raise TapError(f"{TCP_PREFIX}{address}: give the endpoint as {TCP_PREFIX}HOST:PORT")
        try:
            self.sock = socket.create_connection((host, int(port)), timeout=10)
        except OSError as exc:
            raise TapError(f"cannot connect to {TCP_PREFIX}{address}: {exc}") from None
        self.sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)

    def fileno(self) -> int:
        return self.sock.fileno()

    def read(self) -> bytes:
        data = self.sock.recv(CHUNK)
        if not data:
            raise OSError("the endpoint closed the connection")
        return data

    def write(self, data: bytes) -> None:
        self.sock.sendall(data)

    def close(self) -> None:
        self.sock.close()


def open_target(target: str, baudrate: int) -> _Port:
    """The robot's port: ``tcp://HOST:PORT`` or a serial device (TapError if it will not
    open)."""
    if target.startswith(TCP_PREFIX):
        return _TcpPort(target[len(TCP_PREFIX) :])
    return _SerialPort(target, baudrate)


@dataclass(frozen=True)
class TapResult:
    """How a tap ended: ``ended`` in words, the exchanges recorded, the folder."""

    ended: str
    robot_lost: bool
    exchanges: int
    unanswered: int
    folder: Path


def _write_all(fd: int, data: bytes) -> None:
    view = memoryview(data)
    while view:
        done = os.write(fd, view)
        view = view[done:]


class Tap:
    """One tap: the program's pseudo-terminal (:attr:`path`), the robot's port, the run
    folder. :meth:`run` forwards until it ends; :meth:`close` lets everything go."""

    def __init__(
        self,
        config: SimConfig,
        target: str,
        folder: str | Path,
        *,
        link: str | Path | None = None,
        baudrate: int = 9600,
    ) -> None:
        s = config.settings
        self.decoder = TapDecoder(
            s.protocol, s.reply_bytes, (s.frame_start, s.frame_end), s.str_encoding
        )
        self.robot = open_target(target, baudrate)
        try:
            self.recorder = TapRecorder(folder, config, target)
        except (OSError, ValueError) as exc:
            self.robot.close()
            raise TapError(f"cannot record into {folder}: {exc}") from None
        self._master, self._slave = os.openpty()
        tty.setraw(self._slave)  # no echo, no newline translation: replies are binary
        self.path = os.ttyname(self._slave)
        self.link: Path | None = None
        if link is not None:
            self.link = Path(link)
            if os.path.lexists(self.link):
                self.close()
                raise TapError(f"{self.link} exists already; give --link a free name")
            os.symlink(self.path, self.link)
        self.bytes_sent = 0
        self.bytes_received = 0

    def run(
        self,
        program: Sequence[str] | None = None,
        stop: threading.Event | None = None,
        on_ready: Callable[[str], None] | None = None,
    ) -> TapResult:
        """Forward both ways until the program exits, ``stop`` is set or the robot goes;
        record every exchange; close everything; say how it ended."""
        if on_ready is not None:
            on_ready(self.path)
        child = None
        if program is not None:
            env = {**os.environ, "SIMMER_TAP_PORT": self.path}
            argv = [part.replace("{port}", self.path) for part in program]
            child = subprocess.Popen(argv, env=env)  # the user's own program
        ended, lost = "stopped", False
        try:
            ended, lost = self._forward(child, stop)
        finally:
            status = None
            if child is not None:
                if child.poll() is None:
                    child.terminate()
                status = child.wait()
            ended += "" if status is None else f" (its exit status {status})"
            unanswered = self.decoder.unanswered()
            for exchange in unanswered:
                self.recorder.record(exchange)
            self.recorder.close(
                ended,
                lost,
                bytes_sent=self.bytes_sent,
                bytes_received=self.bytes_received,
                stray=self.decoder.stray,
                program=list(program) if program else None,
                program_status=status,
            )
            self.close()
        return TapResult(
            ended, lost, self.recorder.exchanges, len(unanswered), self.recorder.folder
        )

    def _forward(
        self, child: subprocess.Popen[bytes] | None, stop: threading.Event | None
    ) -> tuple[str, bool]:
        """The loop: (how it ended, whether the robot was lost)."""
        master, robot = self._master, self.robot
        with selectors.DefaultSelector() as selector:
            selector.register(master, selectors.EVENT_READ, "program")
            selector.register(robot.fileno(), selectors.EVENT_READ, "robot")
            while True:
                for key, _ in selector.select(SILENCE):
                    now = time.time()
                    if key.data == "program":
                        data = os.read(master, CHUNK)
                        try:
                            robot.write(data)
                        except OSError as exc:
                            return f"the robot was lost: writing to it failed ({exc})", True
                        self.bytes_sent += len(data)
                        self.decoder.sent(data, now)
                    else:
                        try:
                            data = robot.read()
                        except OSError as exc:
                            return f"the robot was lost: {exc}", True
                        _write_all(master, data)
                        self.bytes_received += len(data)
                        self._record(self.decoder.received(data, now))
                self.decoder.quiet(time.time())
                if child is not None and child.poll() is not None:
                    return "the program exited", False
                if stop is not None and stop.is_set():
                    return "stopped by hand (Ctrl-C)", False

    def _record(self, done: list[Exchange]) -> None:
        for exchange in done:
            self.recorder.record(exchange)

    def close(self) -> None:
        """Close both ports and remove the link (again: nothing)."""
        self.robot.close()
        for fd in (self._master, self._slave):
            with contextlib.suppress(OSError):
                os.close(fd)
        self._master = self._slave = -1
        if self.link is not None and self.link.is_symlink():
            with contextlib.suppress(OSError):
                self.link.unlink()
            self.link = None
