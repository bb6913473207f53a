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

* Clock reads made by the standard library's or an installed package's code (the caller's
  file says which) never move the clock and are not counted as reads (``!peek``): how often
  a library reads the clock is its business, not the program's.
* The standard library's waits for another process (``subprocess``, ``multiprocessing``:
  ``Popen.wait`` with a timeout sleeps and reads the clock in a loop) keep the wall clock
  for their sleeps and reads: that process runs in real time, and how many turns its wait
  took must not show in the simulation (``pygame.font.SysFont`` waits so for ``fc-list``).
* Polls on the simulator's connections wait in simulated time: ``select`` (``select``,
  ``poll`` and ``epoll`` objects) and ``selectors`` with a timeout, a socket with a timeout or
  non-blocking, a serial port's ``in_waiting``. (``select.kqueue``, macOS's, used directly, is
  not: its ``selectors`` class is.) Each first makes sure that everything written was taken
  and that every reply byte the simulator has sent has arrived (the clock message's `` +``
  answers how many it sent), so the first poll after a reply sees it whatever the machine's
  speed; then, if nothing is ready, a timeout is a sleep of that long, and a zero-timeout poll
  counts as a clock read (the busy-wait rule). A wait on anything else (a child's pipes) is a
  wall-clock wait.
* Threads: simulated time moves only when every thread of the program is waiting for it.
  After its sleep (or a read that moved the clock), a thread returns only when every reply
  byte sent has arrived, no two-port reply waits for a thread that polls the reply port, and
  every other thread is back in a wait (a sleep, a poll, a read on the simulator with
  nothing due, a lock or queue), at most :data:`SETTLE_WAIT` wall seconds.

Only the standard library is used, so the program starts as fast as it would by hand. If the
program's environment has a ``sitecustomize`` of its own, it is run afterwards. The syntax
stays that of Python 3.8.
"""

from __future__ import annotations

import functools
import math
import os
import select
import selectors
import socket
import struct
import sys
import sysconfig
import threading
import time
import weakref
from collections.abc import Callable, Iterable
from typing import Any

try:
    import fcntl
    import termios

    _FIONREAD: int | None = termios.FIONREAD
    _MODEM_LINES = {
        getattr(termios, name)
        for name in ("TIOCMBIS", "TIOCMBIC", "TIOCMSET", "TIOCMGET")
        if hasattr(termios, name)
    }
    """The modem-control ioctls, which a pseudo-terminal refuses (the virtual RPLidar's)."""
except ImportError:  # Windows: no byte counts, no waiting for them
    fcntl = None  # type: ignore[assignment]
    _FIONREAD = None
    _MODEM_LINES = set()

_HEADER = struct.Struct("<BH")
MAX_SLEEP = 1e9
"""The longest ``time.sleep`` in simulated seconds: the simulator's ``MAX_ABS_VALUE`` (this
module imports nothing of SimMeR's). A longer one raises OverflowError here, as Python's own
``time.sleep`` does past its limit: said at the call, in the program's traceback, rather than
a "refused clock message" from the simulator's log."""
SETTLE_WAIT = 5.0
"""Wall seconds a thread whose sleep is over waits for the program to settle (every reply
byte arrived, every other thread back in a wait). A thread that never waits (it computes, or
blocks on something else than the simulator) would otherwise hold every sleep; past this the
clock goes on without it, said once, and it is not waited for again."""
_LOCAL = {"127.0.0.1", "localhost", "::1"}
_SCANNERS: set[int] = set()
"""The program's descriptors of the virtual RPLidar (``SIMMER_LIDAR_SERIAL``)."""
SCANNER_STEP = 0.01
"""Simulated seconds a timed wait on the virtual RPLidar takes at a time: a scanner sends
unasked, so the wait ends within this of its data coming (a whole timeout at once would let
several scans pile up, which the ``rplidar`` package then throws away)."""
_REAL_SLEEP = time.sleep
_REAL_IOCTL = fcntl.ioctl if fcntl is not None else None
_REAL_SELECT = select.select


def _library_folders() -> tuple[str, ...]:
    """Folders whose code is a library's, not the program's: the standard library, the
    installed packages, and this shim."""
    folders = {os.path.dirname(os.path.abspath(__file__))}
    for name in ("stdlib", "platstdlib", "purelib", "platlib"):
        path = sysconfig.get_paths().get(name)
        if path:
            folders.add(os.path.abspath(path))
    for path in sys.path:
        if path.endswith(("site-packages", "dist-packages")):
            folders.add(os.path.abspath(path))
    return tuple(folder + os.sep for folder in folders)


def _inq(fd: int) -> int:
    """Bytes waiting to be read on ``fd`` (0 where that cannot be asked)."""
    if _REAL_IOCTL is None or _FIONREAD is None or fd < 0:
        return 0
    try:
        return int(struct.unpack("i", _REAL_IOCTL(fd, _FIONREAD, b"\0\0\0\0"))[0])
    except OSError:
        return 0


class _Clock:
    """The connection that carries clock messages; one at a time, from any thread."""

    def __init__(self, host: str, port: int, connect: Callable[..., Any]) -> None:
        self._address = (host, port)
        self._connect = connect
        self._sock: socket.socket | None = None
        self._lock = threading.Lock()
        self.before = 0
        """Bytes of the answers read before the last one (the simulator's count of bytes
        sent, in the last answer, includes these and not that answer)."""
        self._read_total = 0

    def ask(self, message: str) -> list[float]:
        """Send a clock message; its answer's values (the simulated time first)."""
        with self._lock:
            if self._sock is None:
                sock = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
                self._connect(sock, self._address)
                sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
                self._sock = sock
            self._sock.sendall(message.encode("ascii") + b"\n")
            width, count = _HEADER.unpack(self._read(_HEADER.size))
            values = self._read(width * count)
            self.before = self._read_total
            self._read_total += _HEADER.size + width * count
        if count not in (1, 3) or width not in (4, 8):
            raise RuntimeError(f"SimMeR answered {message!r} with {count} values of {width} bytes")
        answer = [float(v) for (v,) in struct.iter_unpack("<d" if width == 8 else "<f", values)]
        if math.isnan(answer[0]):  # the simulator refused it
            raise RuntimeError(f"SimMeR refused the clock message {message!r}; see its log")
        return answer

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

    def ask(self, message: str, written: int | None = None) -> list[float]:
        """A clock message carrying the count (default: every byte written so far): the
        simulator acts on it once it has taken that many. Its answer's values."""
        written = self.total if written is None else written
        counts = message.endswith(" +")
        if counts:
            message = message[:-2]
        answer = self.clock.ask(f"{message} @{written}" + (" +" if counts else ""))
        self.confirmed = max(self.confirmed, written)
        return answer

    def sync_before_reply(self) -> None:
        """A reply connection is about to open: wait until the simulator has taken everything
        written so far (if anything new) but what waits on a two-port message connection
        still open, which the simulator takes when it accepts the reply connection."""
        still_open = sum(size for sock, size in list(self.two_port.items()) if sock.fileno() >= 0)
        written = self.total - still_open
        if written > self.confirmed:
            self.ask("!peek", written)

    def before(self, key: Any) -> None:
        """About to write on connection ``key``: first let the simulator take what was
        written on another one."""
        last = self.last() if isinstance(self.last, weakref.ref) else self.last
        if last != key and self.total > self.confirmed:
            self.ask("!peek")

    def wrote(self, key: Any, size: int) -> None:
        with self.lock:
            self.total += max(size, 0)
            if key in self.two_port:
                self.two_port[key] += max(size, 0)
        self.last = weakref.ref(key) if isinstance(key, socket.socket) else key


class _Program:
    """What the shim knows of the program: the simulated time it last saw, the bytes that
    arrived from the simulator, its threads' waits (module doc)."""

    def __init__(self, written: _Written) -> None:
        self.written = written
        self.now = 0.0
        self.cond = threading.Condition()
        self.moves = 0
        """How many times the clock was seen to move (a reply poller waits for the next)."""
        self.waits: dict[int, Any] = {}
        """Threads in a wait with nothing due: None, or the socket or fd it reads."""
        self.pollers: set[int] = set()
        """Threads that opened a two-port reply connection."""
        self.ignored: set[int] = set()
        self.received = 0
        """Bytes read from the simulator's connections, and those left unread at a close."""
        self.sockets: weakref.WeakSet[socket.socket] = weakref.WeakSet()
        self.fds: set[int] = set()
        self.forgiven = 0
        self.warned = False

    # ------------------------------------------------------------------ time

    def ask(self, message: str) -> list[float]:
        answer = self.written.ask(message)
        self.now = max(self.now, answer[0])
        return answer

    def sleep(self, seconds: float) -> None:
        """Sleep in simulated time, then let the program settle."""
        before = self.now
        with self.waiting():
            value = self.ask(f"!sleep {seconds!r}")[0]
        self.moved(value > before)

    def read(self, library: bool) -> float:
        """A clock read: the program's own counts toward the busy-wait rule (and may move
        the clock); a library's never moves it."""
        if library:
            return self.ask("!peek")[0]
        before = self.now
        value = self.ask("!time")[0]
        self.moved(value > before)
        return value

    def moved(self, moved: bool) -> None:
        """The clock was seen to move (or not): with other threads, wake the reply pollers
        and let the program settle before going on."""
        if not moved or not self.others():
            return
        with self.cond:
            self.moves += 1
            self.cond.notify_all()
        self.settle()

    # ------------------------------------------------------------------ threads

    def others(self) -> list[threading.Thread]:
        """The program's other threads still running, that are waited for."""
        me = threading.current_thread()
        return [
            t
            for t in threading.enumerate()
            if t is not me
            and t.ident not in self.ignored
            and not isinstance(t, threading._DummyThread)
        ]

    def waiting(self, target: Any = None) -> _Waiting:
        """A context in which this thread waits with nothing due (``target``: the socket or
        fd it reads, whose bytes, once there, end the wait)."""
        return _Waiting(self, target)

    def quiet(self, thread: threading.Thread, frames: dict[int, Any]) -> bool:
        """Whether ``thread`` waits with nothing due to it: in a shimmed wait whose socket or
        fd holds nothing, or blocked on a lock, queue or event of the program's."""
        ident = thread.ident
        if ident is None:
            return True  # not started yet
        if ident in self.waits:
            target = self.waits[ident]
            if target is None:
                return True
            fd = target if isinstance(target, int) else target.fileno()
            return _inq(fd) == 0
        frame = frames.get(ident)
        if frame is None:
            return True  # exited meanwhile
        name = frame.f_code.co_filename.replace(os.sep, "/")
        return bool(name.endswith(("/threading.py", "/queue.py", "/concurrent/futures/thread.py")))

    def settle(self) -> None:
        """Return once every reply byte the simulator sent has arrived, no two-port reply
        waits for another thread that polls the reply port, and every other thread is in a
        wait with nothing due (at most :data:`SETTLE_WAIT` wall seconds)."""
        deadline = None
        with self.waiting():
            while True:
                others = self.others()
                if not others:
                    return
                _now, sent, owed = self.ask("!peek +")
                polling = self.pollers & {t.ident for t in others}
                if owed and polling:
                    with self.cond:
                        self.moves += 1  # a reply waits: the pollers go and get it
                        self.cond.notify_all()
                frames = sys._current_frames()
                late = [t for t in others if not self.quiet(t, frames)]
                arrived = self.arrived() + self.forgiven >= sent
                if arrived and not late and not (owed and polling):
                    return
                now = _wall()
                if deadline is None:
                    deadline = now + SETTLE_WAIT
                elif now > deadline:
                    self.give_up(late, int(sent) - self.arrived() - self.forgiven)
                    return
                with self.cond:
                    self.cond.wait(0.0005)

    def give_up(self, late: list[threading.Thread], missing: int) -> None:
        """Past :data:`SETTLE_WAIT`: go on without the threads that kept running (not waited
        for again) and the bytes that never arrived; say so once."""
        self.ignored.update(t.ident for t in late if t.ident is not None)
        self.forgiven += max(missing, 0)
        if not self.warned:
            self.warned = True
            names = ", ".join(t.name for t in late) or "none"
            sys.stderr.write(
                f"simmer: after a sleep the program did not settle within {SETTLE_WAIT:g} wall "
                f"seconds (SETTLE_WAIT): threads still running: {names}; reply bytes not "
                f"arrived: {max(missing, 0)}. The clock goes on without them, so this run may "
                "not repeat exactly (docs/protocol.md, 'Threads').\n"
            )

    def empty_poll(self, seen: int) -> None:
        """A reply connection came back empty: with other threads, wait until the clock has
        moved since ``seen`` (or a reply waits), so a thread polling the reply port in a loop
        waits for simulated time like a sleep; without them, return at once."""
        if not self.others():
            return
        with self.waiting(), self.cond:
            while self.moves == seen:
                self.cond.wait(0.05)
                if self.moves == seen and not self.others():
                    return

    # ------------------------------------------------------------------ bytes

    def track(self, sock: socket.socket) -> None:
        self.sockets.add(sock)

    def got(self, size: int) -> None:
        if size > 0:
            with self.cond:
                self.received += size

    def closing(self, sock: socket.socket) -> None:
        """A connection to the simulator closes: what it held unread arrived all the same."""
        if sock in self.sockets:
            self.got(_inq(sock.fileno()))
            self.sockets.discard(sock)

    def arrived(self) -> int:
        """Bytes from the simulator that reached the program: read, or waiting to be read."""
        total = self.received + self.written.clock.before
        for sock in list(self.sockets):
            total += _inq(sock.fileno())
        for fd in list(self.fds):
            total += _inq(fd)
        return total

    def poll(
        self, ready: Callable[[], bool], timeout: float | None, step: float | None = None
    ) -> bool:
        """A poll for the simulator's bytes (see the module doc): sync, wait for every byte
        sent to arrive, and if nothing is ready wait ``timeout`` simulated seconds (None:
        not at all, the caller blocks); a zero timeout counts as a clock read. With ``step``
        the wait is taken ``step`` seconds at a time and ends once something is ready (the
        virtual RPLidar's stream, which a device sends unasked). Whether anything is ready."""
        before = self.now
        message = "!time +" if timeout == 0 else "!peek +"
        _now, sent, _owed = self.ask(message)
        self.wait_arrived(int(sent))
        if ready():
            return True
        if timeout is None:
            return False
        if timeout > 0:
            left = min(float(timeout), MAX_SLEEP)
            while left > 0:
                self.sleep(left if step is None else min(step, left))
                left = 0.0 if step is None else left - step
                _now, sent, _owed = self.ask("!peek +")
                self.wait_arrived(int(sent))
                if ready():
                    return True
            return False
        self.moved(self.now > before)
        return False

    def wait_arrived(self, sent: int) -> None:
        """Wait (wall time, briefly) until ``sent`` bytes from the simulator have arrived: a
        pseudo-terminal delivers what its master writes a little later."""
        deadline = None
        while self.arrived() + self.forgiven < sent:
            now = _wall()
            if deadline is None:
                deadline = now + SETTLE_WAIT
            elif now > deadline:
                self.give_up([], sent - self.arrived() - self.forgiven)
                return
            _REAL_SLEEP(0.0001)


def _wall() -> float:
    """The wall clock (the shim's own limits)."""
    return _REAL_MONOTONIC()


_REAL_MONOTONIC = time.monotonic


class _Waiting:
    """While inside: this thread waits with nothing due (see :meth:`_Program.waiting`)."""

    def __init__(self, program: _Program, target: Any) -> None:
        self.program = program
        self.target = target
        self.ident = threading.get_ident()
        self.outer = False

    def __enter__(self) -> None:
        waits = self.program.waits
        self.outer = self.ident not in waits
        if self.outer:
            waits[self.ident] = self.target
            with self.program.cond:
                self.program.cond.notify_all()

    def __exit__(self, *exc: object) -> None:
        if self.outer:
            self.program.waits.pop(self.ident, None)


def _ports(name: str) -> set[int]:
    return {int(port) for port in os.environ.get(name, "").split(",") if port.isdigit()}


_IN_CHILD = [False]
"""Whether this process is one the program started (set by :func:`_refuse_in_children`): its
clock reads are then the machine's."""


def _process_waits() -> tuple[str, ...]:
    """The standard library's files that wait for other processes (see the module doc)."""
    stdlib = os.path.abspath(sysconfig.get_paths()["stdlib"])
    return (os.path.join(stdlib, "subprocess.py"), os.path.join(stdlib, "multiprocessing") + os.sep)


def _install(address: str) -> None:
    host, _, port = address.rpartition(":")
    real_connect = socket.socket.connect
    real_connect_ex = socket.socket.connect_ex
    clock = _Clock(host, int(port), real_connect)
    written = _Written(clock)
    program = _Program(written)
    epoch = float(os.environ.get("SIMMER_EPOCH", "0"))
    library = _library_folders()
    process_waits = _process_waits()
    real_time, real_time_ns = time.time, time.time_ns
    real_monotonic_ns = time.monotonic_ns

    def from_library(frame: Any) -> bool:
        """Whether the clock read was made by a library's code (see the module doc)."""
        name = frame.f_code.co_filename
        return bool(name.startswith((*library, "<frozen")))

    def waits_on_a_process(frame: Any) -> bool:
        """Whether the caller is the standard library waiting for another process."""
        return bool(frame.f_code.co_filename.startswith(process_waits))

    def sleep(seconds: float) -> None:
        """Advance the simulation by ``seconds`` (lockstep) and return when it has."""
        if waits_on_a_process(sys._getframe(1)):
            _REAL_SLEEP(seconds)
            return
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
        program.sleep(seconds)

    def clock_read(simulated: Callable[[float], Any], machine: Callable[[], Any]) -> Any:
        """A clock read: ``simulated`` of the simulated time, or the ``machine`` clock in a
        child process or the standard library's wait for another process (module doc)."""

        def read() -> Any:
            caller = sys._getframe(1)
            if _IN_CHILD[0] or waits_on_a_process(caller):
                return machine()
            return simulated(program.read(from_library(caller)))

        # partial objects, like the built-ins they replace, do not bind as methods when a
        # library keeps one as a class attribute (pyserial's ``TIME = time.monotonic``)
        return functools.partial(read)

    def nanoseconds(seconds: float) -> int:
        return round(seconds * 1e9)

    time.sleep = functools.partial(sleep)
    time.monotonic = time.perf_counter = clock_read(float, _REAL_MONOTONIC)
    time.time = clock_read(lambda now: epoch + now, real_time)
    time.monotonic_ns = time.perf_counter_ns = clock_read(nanoseconds, real_monotonic_ns)
    time.time_ns = clock_read(lambda now: nanoseconds(epoch + now), real_time_ns)

    ports: dict[int, int] = {}
    for pair in filter(None, os.environ.get("SIMMER_PORT_MAP", "").split(",")):
        standard, _, actual = pair.partition("=")
        ports[int(standard)] = int(actual)
    local = _LOCAL | {os.environ.get("SIMMER_HOST", "127.0.0.1")}
    message_ports = _ports("SIMMER_MESSAGE_PORTS")
    reply_ports = _ports("SIMMER_REPLY_PORTS")
    two_port_rx = _ports("SIMMER_PORT_RX")
    roles: weakref.WeakKeyDictionary[socket.socket, str] = weakref.WeakKeyDictionary()
    seen: weakref.WeakKeyDictionary[socket.socket, int] = weakref.WeakKeyDictionary()
    """Each reply connection: the clock's moves when it opened (an empty one waits for more)."""
    answered: weakref.WeakSet[socket.socket] = weakref.WeakSet()
    """Reply connections that brought something."""

    def redirect(address: Any) -> tuple[Any, str | None]:
        """Where to connect instead, and the connection's role (None: not the simulator)."""
        if not (isinstance(address, tuple) and len(address) >= 2 and address[0] in local):
            return address, None
        port = ports.get(address[1], address[1])
        role = "message" if port in message_ports else "reply" if port in reply_ports else None
        return (address[0], port, *address[2:]), role

    def opening(sock: socket.socket, target: Any, role: str | None) -> None:
        """Before a connection to the simulator opens: know its role (a non-blocking connect
        raises before it is done)."""
        if role == "reply":
            written.sync_before_reply()
            program.pollers.add(threading.get_ident())
            seen[sock] = program.moves
        if role is not None:
            roles[sock] = role
            program.track(sock)
        if role is not None and target[1] in two_port_rx:
            written.two_port[sock] = 0

    def connect(self: socket.socket, address: Any) -> None:
        target, role = redirect(address)
        opening(self, target, role)
        real_connect(self, target)

    def connect_ex(self: socket.socket, address: Any) -> int:
        target, role = redirect(address)
        opening(self, target, role)
        return int(real_connect_ex(self, target))

    real_send = socket.socket.send
    real_sendall = socket.socket.sendall
    real_recv = socket.socket.recv
    real_recv_into = socket.socket.recv_into
    real_close = socket.socket.close

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

    def readable(sock: socket.socket) -> Callable[[], bool]:
        return lambda: bool(_REAL_SELECT([sock], [], [], 0)[0])

    def receiving(
        self: socket.socket, receive: Callable[[], Any], size: Callable[[Any], int]
    ) -> Any:
        """A read on a connection to the simulator: counted; a timeout is simulated time, a
        non-blocking read a poll (module doc); an empty reply connection a poll too."""
        role = roles.get(self)
        if role is None:
            return receive()
        timeout = self.gettimeout()
        if role == "reply" or _inq(self.fileno()) > 0:  # a reply connection is served at once
            data = receive()
        elif timeout is None:
            with program.waiting(self):
                data = receive()
        else:
            if not program.poll(readable(self), timeout) and timeout > 0:
                raise socket.timeout("timed out")
            data = receive()
        got = size(data)
        program.got(got)
        if role == "reply" and got:
            answered.add(self)
        elif role == "reply" and self not in answered:  # closed with nothing: a poll
            program.empty_poll(seen.get(self, program.moves))
        return data

    def recv(self: socket.socket, bufsize: int, *args: Any) -> bytes:
        return receiving(self, lambda: real_recv(self, bufsize, *args), len)  # type: ignore[no-any-return]

    def recv_into(self: socket.socket, buffer: Any, *args: Any) -> int:
        return receiving(self, lambda: real_recv_into(self, buffer, *args), int)  # type: ignore[no-any-return]

    def close(self: socket.socket) -> None:
        program.closing(self)
        real_close(self)

    socket.socket.connect = connect  # type: ignore[method-assign,assignment]
    socket.socket.connect_ex = connect_ex  # type: ignore[method-assign,assignment]
    socket.socket.send = send  # type: ignore[method-assign,assignment]
    socket.socket.sendall = sendall  # type: ignore[method-assign,assignment]
    socket.socket.recv = recv  # type: ignore[method-assign,assignment]
    socket.socket.recv_into = recv_into  # type: ignore[method-assign,assignment]
    socket.socket.close = close  # type: ignore[method-assign,assignment]
    _patch_select(
        program,
        lambda fd: fd in program.fds or any(s.fileno() == fd for s in list(program.sockets)),
    )
    serials = [os.environ.get(name, "") for name in ("SIMMER_SERIAL", "SIMMER_LIDAR_SERIAL")]
    if any(serials):
        lidar = os.path.realpath(serials[1]) if serials[1] else None
        devices = {os.path.realpath(path) for path in serials if path}
        _count_serial(devices, written, program, lidar)


def _fd(item: Any) -> int:
    return item if isinstance(item, int) else int(item.fileno())


def _patch_select(program: _Program, ours: Callable[[int], bool]) -> None:
    """``select.select`` and the ``selectors``, on a connection to the simulator, wait in
    simulated time (module doc); on anything else (a child process's pipes, the standard
    input) they wait as Python would."""

    def select_(
        rlist: Iterable[Any], wlist: Iterable[Any], xlist: Iterable[Any], timeout: Any = None
    ) -> Any:
        rlist, wlist, xlist = list(rlist), list(wlist), list(xlist)
        if not any(ours(_fd(item)) for item in rlist + wlist + xlist):
            return _REAL_SELECT(rlist, wlist, xlist, timeout)  # a wait on something else

        def ready() -> bool:
            return any(_REAL_SELECT(rlist, wlist, xlist, 0))

        step = SCANNER_STEP if any(_fd(item) in _SCANNERS for item in rlist) else None
        if program.poll(ready, None if timeout is None else max(float(timeout), 0.0), step):
            return _REAL_SELECT(rlist, wlist, xlist, 0)
        if timeout is None:
            with program.waiting():
                return _REAL_SELECT(rlist, wlist, xlist)
        return _REAL_SELECT(rlist, wlist, xlist, 0)

    select.select = select_
    if hasattr(select, "poll"):
        select.poll = _poll_factory(select.poll, program, ours, 1000.0)  # type: ignore[misc]
    if hasattr(select, "epoll"):
        select.epoll = _poll_factory(select.epoll, program, ours, 1.0)  # type: ignore[misc]
    for name in (
        "SelectSelector",
        "PollSelector",
        "EpollSelector",
        "DevpollSelector",
        "KqueueSelector",
    ):
        cls = getattr(selectors, name, None)
        if cls is not None:
            _patch_selector(cls, program, ours)


def _poll_factory(
    real: Any, program: _Program, ours: Callable[[int], bool], per_second: float
) -> Any:
    """``select.poll`` or ``select.epoll`` made to wait in simulated time on a connection to
    the simulator, as ``select.select`` does (the ``selectors`` made before the shim keep the
    real ones). ``per_second``: the poll's timeout unit (milliseconds for ``poll``, seconds
    for ``epoll``); None or a negative timeout waits for ever."""

    class Poll:
        __doc__ = real.__doc__

        def __init__(self, *args: Any, **kwargs: Any) -> None:
            self._real = real(*args, **kwargs)
            self._fds: set[int] = set()

        def __getattr__(self, name: str) -> Any:
            return getattr(self._real, name)

        def __enter__(self) -> Any:
            return self

        def __exit__(self, *exc: object) -> None:
            self._real.close()

        def register(self, fd: Any, *mask: Any) -> None:
            self._real.register(fd, *mask)
            self._fds.add(_fd(fd))

        def unregister(self, fd: Any) -> None:
            self._real.unregister(fd)
            self._fds.discard(_fd(fd))

        def poll(self, timeout: Any = None, *more: Any) -> Any:
            if not any(ours(fd) for fd in self._fds):
                return self._real.poll(timeout, *more)  # a wait on something else
            forever = timeout is None or timeout < 0
            wait = None if forever else float(timeout) / per_second
            if program.poll(lambda: bool(self._real.poll(0)), wait) or not forever:
                return self._real.poll(0, *more)
            with program.waiting():
                return self._real.poll(timeout, *more)

    if not hasattr(real, "__enter__"):  # a poll object is no context manager
        del Poll.__enter__, Poll.__exit__
    if hasattr(real, "fromfd"):
        Poll.fromfd = staticmethod(real.fromfd)  # type: ignore[attr-defined]
    Poll.__name__ = Poll.__qualname__ = real.__name__
    return Poll


def _patch_selector(cls: Any, program: _Program, ours: Callable[[int], bool]) -> None:
    real = cls.select

    def select_(self: Any, timeout: float | None = None) -> Any:
        if not any(ours(key.fd) for key in self.get_map().values()):
            return real(self, timeout)  # a wait on something else (a child's pipes)
        wait = None if timeout is None else max(float(timeout), 0.0)
        if program.poll(lambda: bool(real(self, 0)), wait) or timeout is not None:
            return real(self, 0)
        with program.waiting():
            return real(self, None)

    cls.select = select_


def _count_serial(
    devices: set[str], written: _Written, program: _Program, lidar: str | None = None
) -> None:
    """Count what the program writes to the virtual serial ports ``devices`` (pyserial opens
    them with ``os.open`` and writes with ``os.write``) and reads from them, and make
    ``in_waiting`` (``ioctl TIOCINQ``) a poll. On the virtual RPLidar (``lidar``) the motor
    line's ioctls (pyserial's ``setDTR``, ``setRTS``), which a pseudo-terminal refuses, do
    nothing, as the scanner's motor follows its ``SET_PWM`` command there."""
    real_open, real_write, real_read, real_close = os.open, os.write, os.read, os.close
    serial = program.fds

    def open_(path: Any, flags: int, *args: Any, **kwargs: Any) -> int:
        fd = real_open(path, flags, *args, **kwargs)
        if isinstance(path, (str, bytes, os.PathLike)):
            where = os.path.realpath(path)
            if where in devices:
                serial.add(fd)
            if where == lidar:
                _SCANNERS.add(fd)
        return fd

    def write(fd: int, data: Any) -> int:
        if fd not in serial:
            return real_write(fd, data)
        written.before(fd)
        size = real_write(fd, data)
        written.wrote(fd, size)
        return size

    def read(fd: int, size: int) -> bytes:
        data = real_read(fd, size)
        if fd in serial:
            program.got(len(data))
        return data

    def close(fd: int) -> None:
        if fd in serial:
            program.got(_inq(fd))
            serial.discard(fd)
        _SCANNERS.discard(fd)
        real_close(fd)

    def ioctl(fd: Any, request: int, *args: Any) -> Any:
        if request == _FIONREAD and _fd(fd) in serial:
            waiting = lambda: _inq(_fd(fd)) > 0  # noqa: E731
            # On the scanner, a look that finds its stream is no busy-wait's clock read
            if _fd(fd) not in _SCANNERS or not program.poll(waiting, None):
                program.poll(waiting, 0)
        if request in _MODEM_LINES and _fd(fd) in _SCANNERS:
            return args[0] if args else 0
        return _REAL_IOCTL(fd, request, *args)

    os.open = open_
    os.write = write
    os.read = read
    os.close = close
    if fcntl is not None:
        fcntl.ioctl = ioctl


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


def _refuse_in_children() -> None:
    """In a process the program started (``multiprocessing``, ``subprocess``, ``os.fork``),
    refuse what would need the simulated clock, with :data:`CHILD_REFUSED`: a clock message (a
    sleep), a connection to the simulator, a write on one it inherited. The clock has one
    program to wait for, and a child's sleeps and messages would land on it as the machine
    schedules them. Its clock reads are the machine's; anything else it does is its own."""
    child = _IN_CHILD
    child[0] = os.environ.setdefault(PROGRAM_PID, str(os.getpid())) != str(os.getpid())
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

    def clock_message(self: _Clock, message: str) -> list[float]:
        refuse("sleep or wait on the simulated clock")
        return ask(self, message)

    _Clock.ask = clock_message  # type: ignore[method-assign]

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
