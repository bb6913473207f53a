"""Runs at the start of a control program launched by ``simmer run --program`` (lockstep).

Python imports ``sitecustomize`` at start-up from the first folder on its path that has one;
``simmer run`` puts this folder first on ``PYTHONPATH`` and sets ``SIMMER_LOCKSTEP``. Then:

* ``time.sleep``, ``time.time``, ``time.monotonic`` and ``time.perf_counter`` (and their
  ``_ns`` forms) follow the simulation's clock: a ``sleep(0.1)`` asks the simulator to advance
  by exactly 0.1 s and returns when it has (``!sleep``); a clock read asks for the time
  (``!time``). Both go over one persistent-protocol connection of their own.
* A connection to 127.0.0.1 on SimMeR's standard ports (61200, 61201, 61202, and the ports the
  configuration names) goes to the ports chosen for this run (``SIMMER_PORT_MAP``), so an
  unmodified program finds its simulator and several runs can share a machine.
* Nothing the program wrote towards the simulator is overtaken: the shim counts the bytes it
  writes on message connections (two-port ``port_rx``, the persistent port, the serial port)
  and every clock message says how many (`` @N``), so the simulator acts on it only after
  taking them all. A message sent on a two-port connection just before ``time.sleep`` is
  therefore taken before the sleep, however the two connections race. The same count is
  synchronised (``!sync @N``) before a reply connection opens and before the program writes
  on another connection than the last, so the simulator takes messages in the order the
  program wrote them. A program that waits for each reply never needs the extra message.
  Bytes on a two-port message connection still open when a reply connection opens are left
  out of that count: the simulator takes them when it accepts the reply connection (a
  program that reads its reply before closing its send connection).

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
import weakref
from collections.abc import Callable
from typing import Any

_HEADER = struct.Struct("<BH")
MAX_SLEEP = 1e9
"""The longest ``time.sleep`` in simulated seconds: the simulator's ``MAX_ABS_VALUE`` (this
module imports nothing of SimMeR's). A longer one raises OverflowError here, as Python's own
``time.sleep`` does past its limit: said at the call, in the program's traceback, rather than
a "refused clock message" from the simulator's log."""
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


class _Written:
    """The bytes the program has written towards the simulator on its message connections,
    and how many of them the simulator has said it took (see the module doc)."""

    def __init__(self, clock: _Clock) -> None:
        self.clock = clock
        self.total = 0
        self.confirmed = 0
        self.last: Any = None  # the connection written to last (a weak reference or an fd)
        self.lock = threading.Lock()
        self.two_port: weakref.WeakKeyDictionary[socket.socket, int] = weakref.WeakKeyDictionary()
        """Bytes written on each two-port message connection (one closed is left out)."""

    def ask(self, message: str, written: int | None = None) -> float:
        """A clock message carrying the count (default: every byte written so far): the
        simulator acts on it once it has taken that many."""
        written = self.total if written is None else written
        value = self.clock.ask(f"{message} @{written}")
        self.confirmed = max(self.confirmed, written)
        return value

    def sync_before_reply(self) -> None:
        """A reply connection is about to open: wait until the simulator has taken everything
        written so far (if anything new) but what waits on a two-port message connection
        still open, which the simulator takes when it accepts the reply connection."""
        still_open = sum(size for sock, size in list(self.two_port.items()) if sock.fileno() >= 0)
        written = self.total - still_open
        if written > self.confirmed:
            self.ask("!sync", written)

    def before(self, key: Any) -> None:
        """About to write on connection ``key``: first let the simulator take what was
        written on another one."""
        last = self.last() if isinstance(self.last, weakref.ref) else self.last
        if last != key and self.total > self.confirmed:
            self.ask("!sync")

    def wrote(self, key: Any, size: int) -> None:
        with self.lock:
            self.total += max(size, 0)
            if key in self.two_port:
                self.two_port[key] += max(size, 0)
        self.last = weakref.ref(key) if isinstance(key, socket.socket) else key


def _ports(name: str) -> set[int]:
    return {int(port) for port in os.environ.get(name, "").split(",") if port.isdigit()}


def _install(address: str) -> None:
    host, _, port = address.rpartition(":")
    real_connect = socket.socket.connect
    real_connect_ex = socket.socket.connect_ex
    clock = _Clock(host, int(port), real_connect)
    written = _Written(clock)
    epoch = float(os.environ.get("SIMMER_EPOCH", "0"))

    def sleep(seconds: float) -> None:
        """Advance the simulation by ``seconds`` (lockstep) and return when it has."""
        seconds = float(seconds)
        if math.isnan(seconds):
            raise ValueError("Invalid value NaN (not a number)")  # as Python's own sleep says
        if seconds < 0:
            raise ValueError("sleep length must be non-negative")
        if seconds > MAX_SLEEP:
            raise OverflowError(
                f"sleep length {seconds:g} s is too large: under SimMeR's lockstep clock a sleep "
                f"is at most {MAX_SLEEP:g} simulated seconds (MAX_SLEEP, as a command's value)"
            )
        written.ask(f"!sleep {seconds!r}")

    def now() -> float:
        return written.ask("!time")

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
    local = _LOCAL | {os.environ.get("SIMMER_HOST", "127.0.0.1")}
    message_ports = _ports("SIMMER_MESSAGE_PORTS")
    reply_ports = _ports("SIMMER_REPLY_PORTS")
    two_port_rx = _ports("SIMMER_PORT_RX")
    roles: weakref.WeakKeyDictionary[socket.socket, str] = weakref.WeakKeyDictionary()

    def redirect(address: Any) -> tuple[Any, str | None]:
        """Where to connect instead, and the connection's role (None: not the simulator)."""
        if not (isinstance(address, tuple) and len(address) >= 2 and address[0] in local):
            return address, None
        port = ports.get(address[1], address[1])
        role = "message" if port in message_ports else "reply" if port in reply_ports else None
        return (address[0], port, *address[2:]), role

    def connect(self: socket.socket, address: Any) -> None:
        target, role = redirect(address)
        if role == "reply":
            written.sync_before_reply()
        real_connect(self, target)
        if role is not None:
            roles[self] = role
        if role is not None and target[1] in two_port_rx:
            written.two_port[self] = 0

    def connect_ex(self: socket.socket, address: Any) -> int:
        target, role = redirect(address)
        if role == "reply":
            written.sync_before_reply()
        result = int(real_connect_ex(self, target))
        if role is not None:
            roles[self] = role
        if role is not None and target[1] in two_port_rx:
            written.two_port[self] = 0
        return result

    real_send = socket.socket.send
    real_sendall = socket.socket.sendall

    def send(self: socket.socket, data: Any, *args: Any) -> int:
        if roles.get(self) != "message":
            return int(real_send(self, data, *args))
        written.before(self)
        sent = int(real_send(self, data, *args))
        written.wrote(self, sent)
        return sent

    def sendall(self: socket.socket, data: Any, *args: Any) -> None:
        if roles.get(self) != "message":
            real_sendall(self, data, *args)
            return
        written.before(self)
        real_sendall(self, data, *args)
        written.wrote(self, memoryview(data).nbytes)

    socket.socket.connect = connect  # type: ignore[method-assign,assignment]
    socket.socket.connect_ex = connect_ex  # type: ignore[method-assign,assignment]
    socket.socket.send = send  # type: ignore[method-assign,assignment]
    socket.socket.sendall = sendall  # type: ignore[method-assign,assignment]
    if os.environ.get("SIMMER_SERIAL"):
        _count_serial(os.path.realpath(os.environ["SIMMER_SERIAL"]), written)


def _count_serial(device: str, written: _Written) -> None:
    """Count what the program writes to the virtual serial port ``device`` (pyserial opens it
    with ``os.open`` and writes with ``os.write``)."""
    real_open, real_write, real_close = os.open, os.write, os.close
    serial: set[int] = set()

    def open_(path: Any, flags: int, *args: Any, **kwargs: Any) -> int:
        fd = real_open(path, flags, *args, **kwargs)
        if isinstance(path, (str, bytes, os.PathLike)) and os.path.realpath(path) == device:
            serial.add(fd)
        return fd

    def write(fd: int, data: Any) -> int:
        if fd not in serial:
            return real_write(fd, data)
        written.before(fd)
        size = real_write(fd, data)
        written.wrote(fd, size)
        return size

    def close(fd: int) -> None:
        serial.discard(fd)
        real_close(fd)

    os.open = open_
    os.write = write
    os.close = close


PROGRAM_PID = "SIMMER_PROGRAM_PID"
"""The environment variable holding the program's process id: set by the first process that
loads this shim (the program; a command that replaces itself keeps its id), inherited by every
process it starts, which is therefore a child."""
CHILD_REFUSED = (
    "a process the program started cannot {what} under simmer run --program: only the "
    "program's own process is on the simulated clock, so do this in the program's process "
    "(in a thread if it must run alongside)"
)
"""What a child process is told when it uses the simulator (a RuntimeError)."""
_CLOCK_READS = ("time", "monotonic", "perf_counter", "time_ns", "monotonic_ns", "perf_counter_ns")
_MACHINE_CLOCK = {name: getattr(time, name) for name in _CLOCK_READS}
"""The clock reads as Python has them (this runs before ``_install`` replaces them)."""


def _refuse_in_children() -> None:
    """In a process the program started (``multiprocessing``, ``subprocess``, ``os.fork``),
    refuse what would need the simulated clock, with :data:`CHILD_REFUSED`: a clock message (a
    sleep), a connection to the simulator, a write on one it inherited. The clock has one
    program to wait for, and a child's sleeps and messages would land on it as the machine
    schedules them. Its clock reads are the machine's; anything else it does is its own."""
    child = [os.environ.setdefault(PROGRAM_PID, str(os.getpid())) != str(os.getpid())]
    if hasattr(os, "register_at_fork"):  # a fork copies the program's memory, shim and all
        os.register_at_fork(after_in_child=lambda: child.__setitem__(0, True))
    simulator = _ports("SIMMER_MESSAGE_PORTS") | _ports("SIMMER_REPLY_PORTS")
    for pair in os.environ.get("SIMMER_PORT_MAP", "").split(","):
        simulator |= {int(port) for port in pair.split("=") if port.isdigit()}
    lockstep = os.environ.get("SIMMER_LOCKSTEP", "").rpartition(":")[2]
    simulator |= {int(lockstep)} if lockstep.isdigit() else set()
    local = _LOCAL | {os.environ.get("SIMMER_HOST", "127.0.0.1")}

    def refuse(what: str) -> None:
        if child[0]:
            raise RuntimeError(CHILD_REFUSED.format(what=what))

    def to_simulator(address: Any) -> bool:
        return isinstance(address, tuple) and address[0] in local and address[1] in simulator

    def connected_to_simulator(sock: socket.socket) -> bool:
        try:
            return to_simulator(sock.getpeername())
        except OSError:  # not connected
            return False

    ask = _Clock.ask

    def clock_message(self: _Clock, message: str) -> float:
        refuse("sleep or wait on the simulated clock")
        return ask(self, message)

    _Clock.ask = clock_message  # type: ignore[method-assign]

    def clock_read(name: str) -> Any:
        simulated, machine = getattr(time, name), _MACHINE_CLOCK[name]
        return functools.partial(lambda: machine() if child[0] else simulated())

    for name in _CLOCK_READS:
        setattr(time, name, clock_read(name))

    def guard_connect(real: Any) -> Any:
        def connect(self: socket.socket, address: Any) -> Any:
            if child[0] and to_simulator(address):
                refuse("connect to the simulator")
            return real(self, address)

        return connect

    def guard_send(real: Any) -> Any:
        def send(self: socket.socket, data: Any, *args: Any) -> Any:
            if child[0] and connected_to_simulator(self):
                refuse("write to the simulator")
            return real(self, data, *args)

        return send

    for name in ("connect", "connect_ex"):
        setattr(socket.socket, name, guard_connect(getattr(socket.socket, name)))
    for name in ("send", "sendall"):
        setattr(socket.socket, name, guard_send(getattr(socket.socket, name)))
    if os.environ.get("SIMMER_SERIAL"):
        _refuse_serial_in_children(os.environ["SIMMER_SERIAL"], child, refuse)


def _refuse_serial_in_children(device: str, child: list[bool], refuse: Any) -> None:
    """Refuse a child's opening of the virtual serial port and its writes on the port it
    inherited (pyserial opens it with ``os.open`` and writes with ``os.write``)."""
    real_open, real_write = os.open, os.write
    try:
        port = os.stat(device)
    except OSError:  # gone: nothing to open or write
        return

    def is_port(fd: int) -> bool:
        try:
            found = os.fstat(fd)
        except OSError:
            return False
        return (found.st_dev, found.st_ino) == (port.st_dev, port.st_ino)

    def open_(path: Any, flags: int, *args: Any, **kwargs: Any) -> int:
        fd = real_open(path, flags, *args, **kwargs)
        if child[0] and is_port(fd):
            os.close(fd)
            refuse("open the simulator's serial port")
        return fd

    def write(fd: int, data: Any) -> int:
        if child[0] and is_port(fd):
            refuse("write to the simulator")
        return real_write(fd, data)

    os.open = open_
    os.write = write


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
    _refuse_in_children()
_chain()
