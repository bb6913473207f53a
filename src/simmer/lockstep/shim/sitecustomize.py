"""Runs at the start of a control program launched by ``simmer run --program`` (lockstep).

Python imports ``sitecustomize`` at start-up from the first folder on its path that has one;
``simmer run`` puts this folder first on ``PYTHONPATH`` and sets ``SIMMER_LOCKSTEP``. Then:

* ``time.sleep``, ``time.time``, ``time.monotonic`` and ``time.perf_counter`` (and their
  ``_ns`` forms) follow the simulation's clock: a ``sleep(0.1)`` asks the simulator to advance
  by exactly 0.1 s and returns when it has (``!sleep``); a clock read asks for the time
  (``!time``). Both go over one persistent-protocol connection of their own.
* A connection to 127.0.0.1 on SimMeR's standard ports (61200, 61201, 61202) goes to the ports
  chosen for this run (``SIMMER_PORT_MAP``), so an unmodified program finds its simulator and
  several runs can share a machine.

Only the standard library is used, so the program starts as fast as it would by hand. If the
program's environment has a ``sitecustomize`` of its own, it is run afterwards.
"""

from __future__ import annotations

import functools
import math
import os
import socket
import struct
import sys
import threading
import time
from collections.abc import Callable
from typing import Any

_HEADER = struct.Struct("<BH")
_LOCAL = {"127.0.0.1", "localhost", "::1"}


class _Clock:
    """The connection that carries clock messages; one at a time, from any thread."""

    def __init__(self, host: str, port: int, connect: Callable[..., Any]) -> None:
        self._address = (host, port)
        self._connect = connect
        self._sock: socket.socket | None = None
        self._lock = threading.Lock()

    def ask(self, message: str) -> float:
        """Send a clock message and return the simulated time it answers with."""
        with self._lock:
            if self._sock is None:
                sock = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
                self._connect(sock, self._address)
                sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
                self._sock = sock
            self._sock.sendall(message.encode("ascii") + b"\n")
            width, count = _HEADER.unpack(self._read(_HEADER.size))
            values = self._read(width * count)
        if count != 1 or width not in (4, 8):
            raise RuntimeError(f"SimMeR answered {message!r} with {count} values of {width} bytes")
        (value,) = struct.unpack("<d" if width == 8 else "<f", values)
        if math.isnan(value):  # the simulator refused it
            raise RuntimeError(f"SimMeR refused the clock message {message!r}; see its log")
        return float(value)

    def _read(self, size: int) -> bytes:
        assert self._sock is not None
        data = b""
        while len(data) < size:
            chunk = self._sock.recv(size - len(data))
            if not chunk:
                raise SystemExit("SimMeR has stopped (the simulated run is over)")
            data += chunk
        return data


def _install(address: str) -> None:
    host, _, port = address.rpartition(":")
    real_connect = socket.socket.connect
    real_connect_ex = socket.socket.connect_ex
    clock = _Clock(host, int(port), real_connect)
    epoch = float(os.environ.get("SIMMER_EPOCH", "0"))

    def sleep(seconds: float) -> None:
        """Advance the simulation by ``seconds`` (lockstep) and return when it has."""
        seconds = float(seconds)
        if seconds < 0:
            raise ValueError("sleep length must be non-negative")
        clock.ask(f"!sleep {seconds!r}")

    def now() -> float:
        return clock.ask("!time")

    # partial objects, like the built-ins they replace, do not bind as methods when a library
    # keeps one as a class attribute (pyserial's ``TIME = time.monotonic``)
    time.sleep = functools.partial(sleep)
    time.monotonic = functools.partial(now)
    time.perf_counter = functools.partial(now)
    time.time = functools.partial(lambda: epoch + now())
    time.monotonic_ns = functools.partial(lambda: round(now() * 1e9))
    time.perf_counter_ns = functools.partial(lambda: round(now() * 1e9))
    time.time_ns = functools.partial(lambda: round((epoch + now()) * 1e9))

    ports: dict[int, int] = {}
    for pair in filter(None, os.environ.get("SIMMER_PORT_MAP", "").split(",")):
        standard, _, actual = pair.partition("=")
        ports[int(standard)] = int(actual)

    def redirect(address: Any) -> Any:
        if isinstance(address, tuple) and len(address) >= 2 and address[0] in _LOCAL:
            port = ports.get(address[1])
            if port is not None:
                return (address[0], port, *address[2:])
        return address

    def connect(self: socket.socket, address: Any) -> None:
        real_connect(self, redirect(address))

    def connect_ex(self: socket.socket, address: Any) -> int:
        return int(real_connect_ex(self, redirect(address)))

    socket.socket.connect = connect  # type: ignore[method-assign,assignment]
    socket.socket.connect_ex = connect_ex  # type: ignore[method-assign,assignment]


def _chain() -> None:
    """Run the next ``sitecustomize`` on the path, if the environment has one."""
    here = os.path.dirname(os.path.abspath(__file__))
    for folder in sys.path:
        if not folder or os.path.abspath(folder) == here:
            continue
        candidate = os.path.join(folder, "sitecustomize.py")
        if os.path.isfile(candidate):
            with open(candidate, encoding="utf-8") as file:
                code = compile(file.read(), candidate, "exec")
            exec(code, {"__name__": "sitecustomize", "__file__": candidate})
            return


if os.environ.get("SIMMER_LOCKSTEP"):
    _install(os.environ["SIMMER_LOCKSTEP"])
_chain()
