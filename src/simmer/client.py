"""The library a control program uses to talk to SimMeR (or to the robot itself).

>>> from simmer.client import connect
>>> with connect() as robot:                    # the persistent protocol on 127.0.0.1:61202
...     robot.drive("w0", 12)                   # +inf: accepted
...     robot.wait_idle()
...     print(robot.read("u0"))

``connect(scheme="two-port")`` speaks SimMeR's original scheme (ports 61200/61201) and
``connect(serial="/dev/pts/3")`` a serial port: the simulator's virtual one or the robot's
Bluetooth port. Add ``framed=True`` to either for SimMeR v1.2's framed text (``[u0]`` ->
``[u0:15.45]``; ``True``/``DRIVE STOP`` read as +inf, ``False``/``Not Found`` as NaN, and the
reply's text is kept in ``last_text``). The calls are the same whichever you choose. Over the
persistent protocol, :meth:`Client.explain` asks why the last message's NaN replies are NaN.
"""

from __future__ import annotations

import json
import logging
import math
import os
import socket
import time
from collections.abc import Iterator, Sequence
from dataclasses import dataclass
from pathlib import Path
from types import TracebackType
from typing import Any, Literal, NamedTuple, Protocol, runtime_checkable

from simmer.errors import ConnectionFailed, PortsError, ReplyTimeout
from simmer.ports import (
    AUTO,
    PORT_RX,
    PORT_TX,
    PORTS_VARIABLE,
    STREAM_PORT,
    environment_ports,
)
from simmer.protocol import (
    DOCUMENT,
    DOCUMENT_HEADER,
    EXPLAIN,
    FRAME_HEADER,
    MAX_DOCUMENT_BYTES,
    MAX_MESSAGE_BYTES,
    META_PREFIX,
    TEXT_WIDTH,
    framed_value,
    read_frame_header,
    read_framed_reply,
    unpack_replies,
)
from simmer.untrusted import parse_json

__all__ = [
    "Address",
    "AskLink",
    "Client",
    "ClockLink",
    "Link",
    "Scan",
    "Scheme",
    "SerialLink",
    "StreamLink",
    "TwoPortLink",
    "address",
    "connect",
]

Scheme = Literal["stream", "two-port", "serial"]
"""How :func:`connect` speaks: the persistent protocol, SimMeR's two-port scheme or a serial
port."""
log = logging.getLogger("simmer.client")


FRAME = ("[", "]")
"""SimMeR v1.2's frame characters (its config's ``frame_start`` and ``frame_end``)."""


class Link(Protocol):
    """What a client needs from a connection: one message in, its reply values out."""

    last_text: str | None
    """The last reply as text, for framed links (None for packed replies)."""

    def exchange(self, message: str) -> list[float]:
        """Send one message and return its replies."""
        ...

    def close(self) -> None:
        """Release the connection."""
        ...


@runtime_checkable
class AskLink(Protocol):
    """A link that can send localization messages (the persistent protocol, in-process)."""

    def ask(self, message: str) -> tuple[list[float], str | None]:
        """Send ``%maze``, ``%show JSON`` or ``%pose X Y H``: the values, or the text answer."""
        ...


@runtime_checkable
class ClockLink(Protocol):
    """A link that can send clock messages (the persistent protocol, or an in-process one)."""

    def clock(self, message: str) -> float:
        """Send ``!sleep S``, ``!idle`` or ``!time``; the simulated time after it."""
        ...


def _recv_exactly(sock: socket.socket, size: int) -> bytes:
    data = bytearray()
    while len(data) < size:
        chunk = sock.recv(size - len(data))
        if not chunk:
            raise ConnectionFailed("the simulator closed the connection in the middle of a reply")
        data += chunk
    return bytes(data)


def _connect_tcp(host: str, port: int, timeout: float) -> socket.socket:
    try:
        sock = socket.create_connection((host, port), timeout=timeout)
    except OSError as exc:
        raise ConnectionFailed(
            f"cannot reach SimMeR at {host}:{port} ({exc.strerror or exc}); "
            "is `simmer run` running?"
        ) from None
    sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
    return sock


class StreamLink:
    """The persistent protocol: one connection, a line per message, a framed reply each."""

    def __init__(self, host: str, port: int, timeout: float) -> None:
        self.address = f"{host}:{port}"
        self.last_text: str | None = None
        self._sock = _connect_tcp(host, port, timeout)
        self._stale = False
        """A reply failed (timed out, garbled): what is left of it is dropped before the next
        message, so the next reply is read from its own frame's start."""

    def _send(self, data: bytes) -> None:
        """Send ``data``, first dropping what is left of a reply that failed (a link that
        loses or delays bytes, such as the robot's Bluetooth, leaves a frame's tail behind)."""
        if self._stale:
            self._stale = False
            before = self._sock.gettimeout()
            self._sock.settimeout(0.0)
            try:
                while self._sock.recv(65536):
                    pass
            except (BlockingIOError, InterruptedError):
                pass
            finally:
                self._sock.settimeout(before)
        self._sock.sendall(data)

    def _header(self, message: str) -> tuple[int, int]:
        """Read a reply frame's header; a garbled one (a byte lost or changed on the way) is
        a reply that did not come, and the next message starts afresh."""
        try:
            width, count = read_frame_header(_recv_exactly(self._sock, FRAME_HEADER.size))
            if not 0 < count <= message.count(",") + 1:  # a value per command, never more
                raise ValueError(f"{count} values for {message.count(',') + 1} commands")
        except ValueError as exc:
            self._stale = True
            raise ReplyTimeout(
                f"garbled reply to {message!r} from {self.address} ({exc}); the next message "
                "starts afresh"
            ) from None
        return width, count

    def exchange(self, message: str) -> list[float]:
        """Send ``message`` as one line and read its frame (a reply that times out or comes
        garbled raises :class:`~simmer.errors.ReplyTimeout`, and its rest is dropped before
        the next message)."""
        try:
            self._send(message.encode() + b"\n")
            width, count = self._header(message)
            return unpack_replies(_recv_exactly(self._sock, width * count), width)
        except TimeoutError:
            self._stale = True
            raise ReplyTimeout(f"no reply to {message!r} from {self.address}") from None
        except OSError as exc:
            raise ConnectionFailed(f"lost the connection to {self.address}: {exc}") from None

    def clock(self, message: str, wait: float | None = None) -> float:
        """Send a clock message (``!sleep S``, ``!idle``, ``!time``); the simulated time.
        ``wait``: wall-clock seconds to wait for the answer instead of the link's timeout (an
        ``!idle`` in real time lasts as long as the move)."""
        if wait is None:
            (value,) = self.exchange(message)
        else:
            before = self._sock.gettimeout()
            self._sock.settimeout(wait)
            try:
                (value,) = self.exchange(message)
            finally:
                self._sock.settimeout(before)
        if math.isnan(value):
            raise ReplyTimeout(f"the simulator refused the clock message {message!r}")
        return value

    def ask(self, message: str) -> tuple[list[float], str | None]:
        """Send a localization message; its values, or the JSON of a document frame."""
        try:
            self._send(message.encode() + b"\n")
            header = _recv_exactly(self._sock, FRAME_HEADER.size)
            if header[:1] == DOCUMENT:
                rest = _recv_exactly(self._sock, DOCUMENT_HEADER.size - FRAME_HEADER.size)
                _, size = DOCUMENT_HEADER.unpack(header + rest)
                if size > MAX_DOCUMENT_BYTES:
                    raise ConnectionFailed(f"{self.address} sent a document of {size} bytes")
                return [], _recv_exactly(self._sock, size).decode("utf-8")
            width, count = read_frame_header(header)
            return unpack_replies(_recv_exactly(self._sock, width * count), width), None
        except TimeoutError:
            self._stale = True
            raise ReplyTimeout(f"no reply to {message[:40]!r} from {self.address}") from None
        except OSError as exc:
            raise ConnectionFailed(f"lost the connection to {self.address}: {exc}") from None

    def explain(self) -> str:
        """Why the last message's NaN replies are NaN, one reason a line ("" if none)."""
        try:
            self._send(EXPLAIN + b"\n")
            width, size = FRAME_HEADER.unpack(_recv_exactly(self._sock, FRAME_HEADER.size))
            if width != TEXT_WIDTH:
                raise ConnectionFailed(f"{self.address} answered '?' with values, not text")
            return _recv_exactly(self._sock, size).decode("utf-8", errors="replace")
        except TimeoutError:
            self._stale = True
            raise ReplyTimeout(f"no answer to '?' from {self.address}") from None
        except OSError as exc:
            raise ConnectionFailed(f"lost the connection to {self.address}: {exc}") from None

    def close(self) -> None:
        """Close the connection."""
        self._sock.close()


def _framed_values(text: str, message: str, frame: tuple[str, str]) -> list[float]:
    try:
        pairs = read_framed_reply(text, *frame)
    except ValueError as exc:
        raise ConnectionFailed(f"reply to {message!r}: {exc}") from None
    return [framed_value(value) for _, value in pairs]


class TwoPortLink:
    """SimMeR's scheme: send on ``port_rx`` and close, then read the reply from ``port_tx``.

    The reply width (4 or 8 bytes) is inferred from the reply's length; with ``frame`` (start
    and end characters) the message is framed and the reply read as SimMeR v1.2's text."""

    def __init__(
        self,
        host: str,
        port_rx: int,
        port_tx: int,
        timeout: float,
        frame: tuple[str, str] | None = None,
    ) -> None:
        self.host, self.port_rx, self.port_tx, self.timeout = host, port_rx, port_tx, timeout
        self.frame = frame
        self.last_text: str | None = None

    def exchange(self, message: str) -> list[float]:
        """One message: connect, send, close; connect, read until closed."""
        frame = self.frame
        payload = f"{frame[0]}{message}{frame[1]}" if frame else message
        with _connect_tcp(self.host, self.port_rx, self.timeout) as out:
            out.sendall(payload.encode())
        data = bytearray()
        with _connect_tcp(self.host, self.port_tx, self.timeout) as back:
            try:
                while chunk := back.recv(65536):
                    data += chunk
            except TimeoutError:
                raise ReplyTimeout(f"no reply to {message!r} within {self.timeout} s") from None
        if frame is not None:
            self.last_text = data.decode("ascii", errors="replace")
            return _framed_values(self.last_text, message, frame)
        if not data:
            raise ConnectionFailed(
                f"the simulator answered {message!r} with nothing: the link lost the reply, "
                "or it speaks SimMeR v1.2's "
                "framed text (protocol = 'framed'); connect with framed=True "
                "(simmer console --framed)"
            )
        count = message.count(",") + 1
        width = len(data) // count if len(data) in (4 * count, 8 * count) else 4
        if not data or len(data) % width:
            raise ConnectionFailed(f"reply of {len(data)} bytes to {message!r} is incomplete")
        return unpack_replies(bytes(data), width)

    def close(self) -> None:
        """Nothing stays open between messages."""


class SerialLink:
    """A serial port (pyserial): a line per message, one packed float per command back; with
    ``frame``, a frame per message and a framed text reply read up to its end character."""

    def __init__(
        self,
        port: str,
        baudrate: int,
        timeout: float,
        width: int,
        frame: tuple[str, str] | None = None,
    ) -> None:
        import serial  # pyserial

        self.width = width
        self.frame = frame
        self.last_text: str | None = None
        try:
            self._port = serial.Serial(port, baudrate=baudrate, timeout=timeout)
        except (serial.SerialException, OSError) as exc:
            raise ConnectionFailed(f"cannot open serial port {port}: {exc}") from None
        self._stale = False
        """A reply timed out: what came of it late is dropped before the next message."""

    def _write(self, data: bytes) -> None:
        """Write ``data``, first dropping the late rest of a reply that timed out (so it is
        never taken for the next message's reply)."""
        if self._stale:
            self._stale = False
            self._port.reset_input_buffer()
        self._port.write(data)

    def exchange(self, message: str) -> list[float]:
        """Write the message and a newline, read one value per command (a reply that does
        not come whole in time raises :class:`~simmer.errors.ReplyTimeout`; its rest is
        dropped before the next message)."""
        if self.frame is not None:
            start, end = self.frame
            self._write(f"{start}{message}{end}".encode())
            data = self._port.read_until(end.encode())
            self.last_text = data.decode("ascii", errors="replace")
            if not data.endswith(end.encode()):
                self._stale = True
                raise ReplyTimeout(f"serial reply to {message!r}: {self.last_text!r} so far")
            return _framed_values(self.last_text, message, self.frame)
        size = self.width * (message.count(",") + 1)
        self._write(message.encode() + b"\n")
        data = self._port.read(size)
        if len(data) < size:
            self._stale = True
            raise ReplyTimeout(f"serial reply to {message!r}: {len(data)} of {size} bytes")
        return unpack_replies(data, self.width)

    def close(self) -> None:
        """Close the port."""
        self._port.close()


@dataclass(frozen=True)
class Scan:
    """A LiDAR's whole scan (:meth:`Client.scan`); unpacks as ``angles, distances``."""

    angles: Any
    """Each beam's angle, degrees clockwise from the LiDAR's front (a NumPy array)."""
    distances: Any
    """Each beam's distance, inches; 0 where the beam returned nothing (a NumPy array)."""
    number: float
    """The scan's number: it grows by one a revolution (NaN if the read failed)."""

    def __iter__(self) -> Iterator[Any]:
        """``angles, distances = robot.scan("l0")``."""
        return iter((self.angles, self.distances))

    def points(
        self, x: float, y: float, heading: float, mount: Sequence[float] = (0.0, 0.0, 0.0)
    ) -> Any:
        """Where the beams met something if the robot is at ``x, y, heading`` (your estimate),
        world inches, (N, 2) (beams with no return left out): what ``robot.show(points=...)``
        draws. ``mount``: the LiDAR's position and rotation on the robot, as configured (its
        ``position`` x, y and ``rotation``; ``robot.maze()`` gives them)."""
        import numpy as np

        mx, my, rotation = (float(v) for v in mount)
        h = math.radians(heading)
        c, s = math.cos(h), math.sin(h)
        cx, cy = x + mx * c - my * s, y + mx * s + my * c
        hit = self.distances > 0
        beam = np.radians(heading + rotation + self.angles[hit])
        d = self.distances[hit]
        return np.column_stack((cx - d * np.sin(beam), cy + d * np.cos(beam)))


class Client:
    """A connection to the simulator or robot; use :func:`connect` to make one.

    With ``lockstep`` (a persistent-protocol link to a simulator on the lockstep clock),
    :meth:`sleep` and :meth:`wait_idle` ask the simulator to advance its clock instead of
    waiting on the wall clock.
    """

    def __init__(self, link: Link, *, lockstep: bool = False) -> None:
        self.link = link
        self._clock = link if lockstep and isinstance(link, ClockLink) else None
        self._scans: dict[str, tuple[Any, str]] = {}
        """Each LiDAR read so far: its beams' angles (a NumPy array) and its whole-scan message."""
        self.cut = 0
        """Points :meth:`show` cut to fit the bounds, in all."""
        self._cut_logged = -math.inf

    @property
    def lockstep(self) -> bool:
        """True if :meth:`sleep` and :meth:`wait_idle` advance the simulator's clock."""
        return self._clock is not None

    def send(self, message: str) -> list[float]:
        """Send a message such as ``"u0,u1"``; one value per command (NaN: rejected/invalid)."""
        return self.link.exchange(message)

    def drive(self, drive_id: str, amount: float) -> float:
        """Start drive ``drive_id`` moving ``amount`` in (or deg): +inf accepted, NaN busy."""
        return self.send(f"{drive_id}-{amount:g}")[0]

    def explain(self) -> str | None:
        """Why the last message's NaN replies are NaN, as the simulator logged it (a reason a
        line, "" if none); None where the link cannot ask (two-port, serial: only the
        persistent protocol has a way to)."""
        return self.link.explain() if isinstance(self.link, StreamLink) else None

    def read(self, device_id: str) -> float:
        """Read one sensor (or motor odometer)."""
        return self.send(device_id)[0]

    def scan(self, lidar_id: str = "l0") -> Scan:
        """The latest whole scan of LiDAR ``lidar_id``: its beams' angles (degrees clockwise
        from the LiDAR's front) and distances (inches, 0: no return) as NumPy arrays, and the
        scan's number. Two messages the first time (``l0--1``: the beams a revolution), then
        one: ``l0--2`` and a read per beam, all answered from one scan (docs/protocol.md)."""
        import numpy as np

        known = self._scans.get(lidar_id)
        if known is None:
            value = self.read(f"{lidar_id}--1")
            if not (math.isfinite(value) and value >= 1 and value == int(value)):
                raise ValueError(f"{lidar_id!r} answered {value!r} for its beams: not a LiDAR")
            beams = int(value)
            angles = np.arange(beams, dtype=np.float64) * (360.0 / beams)
            reads = (f"{lidar_id}-{a!r}" for a in angles.tolist())
            known = self._scans[lidar_id] = (angles, ",".join([f"{lidar_id}--2", *reads]))
        angles, message = known
        values = self.send(message)
        return Scan(angles.copy(), np.asarray(values[1:], dtype=np.float64), values[0])

    def sleep(self, seconds: float) -> None:
        """Let ``seconds`` pass: simulated seconds in lockstep, else wall-clock ones."""
        if self._clock is not None:
            self._clock.clock(f"!sleep {float(seconds)!r}")
        else:
            time.sleep(seconds)

    def wait_idle(self, drive_id: str = "w0", poll: float = 0.01, timeout: float = 600.0) -> None:
        """Wait until no drive is moving (a zero-length move of ``drive_id`` is accepted).

        Over the persistent protocol the simulator itself answers ``!idle`` once no drive
        moves (in simulated time in lockstep, else in real time), so the wait sends no stream
        of busy ``w0-0`` polls; over the two-port scheme or a serial port (the robot) it polls
        every ``poll`` seconds. Either way one ``w0-0`` confirms it.
        """
        if self._clock is not None:
            self._clock.clock("!idle")
        elif isinstance(self.link, StreamLink):
            self.link.clock("!idle", wait=timeout)
        deadline = time.monotonic() + timeout
        while not math.isinf(self.drive(drive_id, 0)):
            if time.monotonic() > deadline:
                raise ReplyTimeout(f"drives still moving after {timeout} s")
            self.sleep(poll)

    # -- localization (the persistent protocol only) ----------------------------------

    def _ask(self, message: str) -> tuple[list[float], str | None]:
        if not isinstance(self.link, AskLink):
            raise ConnectionFailed(
                "the maze and beliefs go over the persistent protocol only: connect() without "
                "scheme or serial (simmer export-map writes the maze for the real robot)"
            )
        return self.link.ask(message)

    def maze(self) -> dict[str, Any]:
        """The maze as the simulator knows it: walls, sizes, wall segments, floor, zones,
        the configured start and every device's mount (docs/localization.md)."""
        _, text = self._ask(META_PREFIX.decode() + "maze")
        if text is None:
            raise ConnectionFailed("the simulator answered '%maze' with values, not the maze")
        data: dict[str, Any] = parse_json(
            text, "the maze", MAX_DOCUMENT_BYTES, "MAX_DOCUMENT_BYTES"
        )
        return data

    def show(
        self,
        particles: Any = None,
        *,
        cells: Any = None,
        pose: Sequence[float] | None = None,
        ellipse: Sequence[float] | None = None,
        cov: Sequence[Sequence[float]] | None = None,
        path: Any = None,
        labels: Sequence[tuple[float, float, str]] = (),
        points: Any = None,
    ) -> int:
        """Show your belief over the maze (the window, videos, the recording); free of
        simulated time. ``particles``: rows of x, y, heading, weight (a NumPy array does);
        ``cells``: a grid of probabilities, row 0 at y = 0; ``pose``: x, y, heading, with its
        uncertainty as ``ellipse`` (semi-axes a, b in inches, angle of a from +x) or ``cov``
        (the 2 x 2 covariance of x and y: a 2-sigma ellipse); ``path``: rows of x, y;
        ``labels``: (x, y, text); ``points``: rows of x, y, world points such as a scan placed
        at your estimate (``robot.scan("l0").points(x, y, heading)``) or your map's. Returns
        how many points were cut to fit the bounds (docs/localization.md; -1: the message was
        dropped, over the shows a simulated second); a cut is logged, at most once a wall
        second. ValueError if the simulator refuses the belief (a grid of over 4,096 cells),
        with its reason.
        """
        data: list[str] = []
        given = _rows(particles)
        rows = [row for row in given if all(map(math.isfinite, row))]
        cut = len(given) - len(rows)
        rows, more = _heaviest(rows, MAX_SHOWN)
        cut += more
        if cells is not None:
            data.append('"cells":' + json.dumps(_rows(cells)))
        if pose is not None:
            data.append('"pose":' + json.dumps([float(v) for v in pose]))
        if cov is not None:
            ellipse = _ellipse(cov)
        if ellipse is not None:
            data.append('"ellipse":' + json.dumps([float(v) for v in ellipse]))
        if path is not None:
            data.append('"path":' + _points(_rows(path)))
        if points is not None:
            placed = [row for row in _rows(points) if all(map(math.isfinite, row))]
            data.append('"points":' + _points(placed))
        if labels:
            data.append(
                '"labels":' + json.dumps([[float(x), float(y), str(t)] for x, y, t in labels])
            )
        head = "%show {" + ",".join(data)
        budget = MAX_MESSAGE_BYTES - len(head) - 20
        text = _particles(rows)
        while len(text) > budget:  # too many digits for one line: the lightest go first
            rows, more = _heaviest(rows, max(1, len(rows) * budget // len(text) - 1))
            cut += more
            text = _particles(rows)
        if rows:
            head += ("," if data else "") + '"particles":' + text
        if cut:
            self._log_cut(cut)
        (value,) = self._ask(head + "}")[0] or [math.nan]
        if math.isnan(value):
            raise ValueError(f"the simulator refused the belief: {self.explain() or 'see its log'}")
        return cut + int(value) if value >= 0 else -1

    def report_pose(self, x: float, y: float, heading: float) -> bool:
        """Tell the simulator where you believe the robot is, for the run's outcome (its error
        over time, when it localized); free of simulated time. False if over the bound (a
        simulated second keeps 60)."""
        (value,) = self._ask(f"%pose {float(x)!r} {float(y)!r} {float(heading)!r}")[0]
        return value == 0.0

    def _log_cut(self, cut: int) -> None:
        self.cut += cut
        now = time.monotonic()
        if now - self._cut_logged >= 1.0:
            self._cut_logged = now
            log.warning(
                "show: %d points cut to fit the bounds (%d in all; at most %d particles a "
                "message, the heaviest kept)",
                cut,
                self.cut,
                MAX_SHOWN,
            )

    def close(self) -> None:
        """Close the connection."""
        self.link.close()

    def __enter__(self) -> Client:
        return self

    def __exit__(
        self, kind: type[BaseException] | None, exc: BaseException | None, tb: TracebackType | None
    ) -> None:
        self.close()


MAX_SHOWN = 2000
"""Particles in one show message (the simulator's bound, simmer.localize.belief)."""


def _rows(value: Any) -> list[list[float]]:
    """Rows of numbers from a list of sequences or a NumPy array (without importing NumPy)."""
    if value is None:
        return []
    if hasattr(value, "tolist"):
        value = value.tolist()
    return [[float(v) for v in row] for row in value]


def _heaviest(rows: list[list[float]], keep: int) -> tuple[list[list[float]], int]:
    """The ``keep`` heaviest particles (last column), in their order; and how many went."""
    if len(rows) <= keep:
        return rows, 0
    chosen = sorted(sorted(range(len(rows)), key=lambda i: -rows[i][3])[:keep])
    return [rows[i] for i in chosen], len(rows) - keep


def _points(rows: list[list[float]]) -> str:
    """Rows of x, y as JSON, to 0.01 in."""
    return "[" + ",".join(f"[{x:.2f},{y:.2f}]" for x, y in rows) + "]"


def _particles(rows: list[list[float]]) -> str:
    """Particles as JSON, x and y to 0.01 in, heading to 0.1 degree, weight to 4 digits."""
    return "[" + ",".join(f"[{x:.2f},{y:.2f},{h:.1f},{w:.4g}]" for x, y, h, w in rows) + "]"


def _ellipse(cov: Sequence[Sequence[float]]) -> tuple[float, float, float]:
    """The 2-sigma ellipse (a, b, angle of a from +x) of a 2 x 2 covariance."""
    sxx, sxy, syy = float(cov[0][0]), float(cov[0][1]), float(cov[1][1])
    mean, diff = (sxx + syy) / 2.0, math.hypot((sxx - syy) / 2.0, sxy)
    big, small = max(mean + diff, 0.0), max(mean - diff, 0.0)
    angle = math.degrees(0.5 * math.atan2(2.0 * sxy, sxx - syy))
    return 2.0 * math.sqrt(big), 2.0 * math.sqrt(small), angle


def _from_env(name: str, default: int) -> int:
    value = os.environ.get(name, "")
    return int(value) if value.isdigit() else default


class Address(NamedTuple):
    """Where the simulator listens (:func:`address`): its host and its three ports."""

    host: str
    """The simulator's address (127.0.0.1: this machine)."""
    port_rx: int
    """The two-port scheme's message port: a program transmits here."""
    port_tx: int
    """The two-port scheme's reply port: a program receives from here."""
    port: int
    """The persistent protocol's port."""


def address() -> Address:
    """Where the simulator listens, from the environment: ``SIMMER_HOST`` (default 127.0.0.1),
    ``SIMMER_PORTS`` (``N`` for ``N``, ``N+1``, ``N+2``, or ``RX,TX,PORT``: what ``simmer
    run --ports`` and ``simmer console --ports`` take), and over it ``SIMMER_PORT_RX``,
    ``SIMMER_PORT_TX`` and ``SIMMER_PORT`` (one each; ``simmer run --program`` sets all of
    them to its run's ports); SimMeR's standard ports for any none names. Raises
    :class:`~simmer.errors.ConnectionFailed` for a ``SIMMER_PORTS`` that names no ports."""
    if os.environ.get(PORTS_VARIABLE, "").strip().lower() == AUTO:
        raise ConnectionFailed(
            f"{PORTS_VARIABLE}=auto picks free ports for simmer run only; set {PORTS_VARIABLE} "
            "to the three ports that simmer run printed (its 'other terminals' line)"
        )
    try:
        chosen = environment_ports()
    except PortsError as exc:
        raise ConnectionFailed(str(exc)) from None
    rx, tx, stream = chosen.resolve(PORT_RX, PORT_TX) if chosen else (PORT_RX, PORT_TX, STREAM_PORT)
    return Address(
        os.environ.get("SIMMER_HOST", "") or "127.0.0.1",
        _from_env("SIMMER_PORT_RX", rx),
        _from_env("SIMMER_PORT_TX", tx),
        _from_env("SIMMER_PORT", stream),
    )


def connect(
    host: str | None = None,
    port: int | None = None,
    *,
    scheme: Scheme | None = None,
    port_rx: int | None = None,
    port_tx: int | None = None,
    serial: str | Path | None = None,
    baudrate: int = 9600,
    width: int = 4,
    timeout: float = 30.0,
    framed: bool = False,
    lockstep: bool | None = None,
) -> Client:
    """Connect with the persistent protocol (default), ``scheme="two-port"``, or ``serial=PATH``.

    ``width`` is the serial reply width (4 for the Arduino and SimMeR's default); TCP replies
    say or reveal their own width. ``framed=True`` speaks SimMeR v1.2's framed text over the
    two-port scheme (the default scheme then) or a serial port; the persistent protocol always
    uses its own frames. Raises :class:`~simmer.errors.ConnectionFailed`.

    Unless given, the address and ports are :func:`address`'s: ``SIMMER_PORTS`` (one setting
    for all three, as ``simmer run --ports`` takes), ``SIMMER_HOST``, ``SIMMER_PORT``,
    ``SIMMER_PORT_RX`` and ``SIMMER_PORT_TX`` (``simmer run --program`` sets them to the run's
    own ports), else 127.0.0.1 and SimMeR's standard ports; ``lockstep`` (for :meth:`Client.
    sleep` and :meth:`Client.wait_idle`) from ``SIMMER_LOCKSTEP``: set it for a program you
    start by hand against ``simmer run --clock lockstep``.
    """
    needed = serial is None and None in (host, port, port_rx, port_tx)
    where = address() if needed else Address("127.0.0.1", PORT_RX, PORT_TX, STREAM_PORT)
    host = where.host if host is None else host
    port = where.port if port is None else port
    port_rx = where.port_rx if port_rx is None else port_rx
    port_tx = where.port_tx if port_tx is None else port_tx
    if lockstep is None:
        lockstep = bool(os.environ.get("SIMMER_LOCKSTEP"))
    if scheme is None:
        scheme = "serial" if serial is not None else ("two-port" if framed else "stream")
    frame = FRAME if framed else None
    link: Link
    if scheme == "serial":
        if serial is None:
            raise ValueError("scheme='serial' needs serial=PATH")
        link = SerialLink(str(serial), baudrate, timeout, width, frame)
    elif scheme == "two-port":
        link = TwoPortLink(host, port_rx, port_tx, timeout, frame)
    else:
        if framed:
            raise ValueError("framed=True is for scheme='two-port' or a serial port")
        link = StreamLink(host, port, timeout)
    return Client(link, lockstep=lockstep)
