"""The link model: the serial link between a program and the robot as it really behaves.

A real robot answers over an HC-05 Bluetooth module: at 9600 baud a byte takes 1.04 ms, a
message waits for the radio (latency, and jitter on top), an Arduino's SoftwareSerial buffer
overflows now and then (a byte lost) or a bit flips, and when the motors brown the robot out
the link is gone for a second or two. :class:`LinkModel` is that link, in simulated time and
from the run's seed alone (one stream per source: ``link:jitter``, ``link:loss``,
``link:corruption``, ``link:corruption-bit``, ``link:dropout``), so a run with it repeats as
one without it does.
:class:`Link` puts it between every transport and the program (the two-port scheme, the
persistent port and the serial port carry their command and reply bytes through it); the
simulator's own messages (clock, localization and ``?`` lines) are not on the robot's link
and pass untouched.

The model: each direction is a wire that carries one message at a time. A message starts
when the wire is free and not before its time (a reply not before its command arrived); it
waits ``latency`` plus up to ``jitter`` (uniform), then its bytes take 10 bits each at
``baud``. Each byte is lost with chance ``loss`` and has one bit flipped with chance
``corruption`` (drawn as gaps between such bytes, so the pattern depends on the byte's place
in the run's bytes, not on how they were split into messages). A message that starts during
a dropout is lost whole. Dropouts start at exponential intervals of mean ``dropout_every``
simulated seconds and last ``dropout_seconds``.
"""

from __future__ import annotations

import math
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any, Protocol

import numpy as np

from simmer.config.link import LinkParams

__all__ = ["Carried", "Link", "LinkClock", "LinkCounts", "LinkModel", "Wire"]

TO_ROBOT = "to robot"
TO_PROGRAM = "to program"


@dataclass(frozen=True)
class Carried:
    """One message over the link: the bytes that arrive, when, and what happened on the way."""

    data: bytes
    arrives: float
    """Simulated time the last byte arrives."""
    lost: int
    corrupted: int
    dropout: bool
    """Whether it started during a dropout (every byte lost)."""


@dataclass
class LinkCounts:
    """What the link did so far (the HUD, the event log and the report show these)."""

    messages: int = 0
    bytes: int = 0
    """Bytes sent over the link (each delayed by the wire)."""
    seconds: float = 0.0
    """Simulated seconds the messages spent on the link, summed."""
    lost: int = 0
    corrupted: int = 0
    dropouts: int = 0
    """Dropouts begun by the time of the last message."""
    in_dropout: int = 0
    """Messages lost whole because they started during a dropout."""

    def as_dict(self) -> dict[str, float]:
        """The counts, for report.json."""
        return dict(self.__dict__)


class _Gaps:
    """Which bytes of the run's byte sequence an event (a loss, a flip) hits: the gaps between
    them are geometric, drawn from one stream, so a byte's fate depends on its place alone."""

    def __init__(self, rng: np.random.Generator, chance: float) -> None:
        self.rng = rng
        self.chance = chance
        self.left = self._gap()
        """Bytes still to pass before the next hit (the hit is byte ``left`` from here)."""

    def _gap(self) -> float:
        if self.chance <= 0:
            return math.inf
        if self.chance >= 1:
            return 0
        return float(self.rng.geometric(self.chance) - 1)

    def hits(self, size: int) -> list[int]:
        """Indices hit among the next ``size`` bytes."""
        found: list[int] = []
        at = 0.0
        while at + self.left < size:
            at += self.left
            found.append(int(at))
            at += 1
            self.left = self._gap()
        self.left -= size - at
        return found


class LinkModel:
    """The link's state and its draws (module doc); pure: no sockets, no clock of its own.

    ``stream(name)`` gives the seeded generator of one source (:meth:`Simulation.stream
    <simmer.world.Simulation.stream>`)."""

    def __init__(self, params: LinkParams, stream: Callable[[str], np.random.Generator]) -> None:
        self.params = params
        self._jitter = stream("link:jitter")
        self._loss = _Gaps(stream("link:loss"), params.loss)
        self._flips = _Gaps(stream("link:corruption"), params.corruption)
        self._bits = stream("link:corruption-bit")
        self._dropout = stream("link:dropout")
        self._free = {TO_ROBOT: 0.0, TO_PROGRAM: 0.0}
        self.counts = LinkCounts()
        self._counted = -1.0
        self.window = (math.inf, math.inf)
        """The current or next dropout: [start, end) in simulated seconds."""
        if params.dropout_every > 0 and params.dropout_seconds > 0:
            start = float(self._dropout.exponential(params.dropout_every))
            self.window = (start, start + params.dropout_seconds)

    def dropped(self, at: float) -> bool:
        """Whether the link is down at simulated time ``at`` (times only move forward);
        every window begun by ``at`` is counted in :attr:`counts`."""
        start, end = self.window
        while at >= end:  # past this window: count it, draw the next
            self._count(start)
            start = end + float(self._dropout.exponential(self.params.dropout_every))
            end = start + self.params.dropout_seconds
            self.window = (start, end)
        if at >= start:
            self._count(start)
            return True
        return False

    def _count(self, start: float) -> None:
        """Count the window starting at ``start`` once."""
        if start != self._counted:
            self._counted = start
            self.counts.dropouts += 1

    def carry(self, data: bytes, now: float, toward: str) -> Carried:
        """Send ``data`` as one message at simulated time ``now``, ``toward`` the robot or the
        program: what arrives and when."""
        p = self.params
        size = len(data)
        after = self._free[TO_ROBOT] if toward == TO_PROGRAM else 0.0
        start = max(now, self._free[toward], after)
        wait = p.latency + p.jitter * float(self._jitter.random())
        arrives = start + wait + size * p.byte_seconds
        self._free[toward] = arrives
        lost = set(self._loss.hits(size))
        hits = self._flips.hits(size)
        bits = [int(self._bits.integers(8)) for _ in hits]  # drawn whatever else is lost
        flips = [(i, bit) for i, bit in zip(hits, bits, strict=True) if i not in lost]
        down = self.dropped(start)
        counts = self.counts
        counts.messages += 1
        counts.bytes += size
        counts.seconds += arrives - now
        if down:
            counts.lost += size
            counts.in_dropout += 1
            return Carried(b"", arrives, size, 0, True)
        out = bytearray(data)
        for index, bit in flips:
            out[index] ^= 1 << bit
        for index in sorted(lost, reverse=True):
            del out[index]
        counts.lost += len(lost)
        counts.corrupted += len(flips)
        return Carried(bytes(out), arrives, len(lost), len(flips), False)


class LinkClock(Protocol):
    """What a :class:`Link` asks of the run's clock (:class:`simmer.clock.Clock`)."""

    def now(self) -> float:
        """The program's simulated time: when what it sends now leaves it."""
        ...

    def advance_to(self, when: float) -> None:
        """The program cannot go on before ``when`` (the lockstep clock moves there; the
        real-time clock is paced by the wall clock and ignores it)."""
        ...


@dataclass
class Link:
    """The link model between the transports and the program (module doc).

    ``hold(seconds, deliver)``: how a reply waits ``seconds`` of simulated time for its
    arrival; on the lockstep clock the program's clock has moved past it already, so it is
    delivered at once; in real time it waits until the simulation gets there
    (:meth:`simmer.clock.Clock.at`).
    ``emit(what, value, detail)``: record what the link did in the run's events."""

    model: LinkModel
    clock: LinkClock
    hold: Callable[[float, Callable[[], None]], None]
    emit: Callable[[str, float, str], None] = field(default=lambda what, value, detail: None)

    def inbound(self, data: bytes) -> bytes:
        """A command message from the program, as it reaches the robot (maybe shorter,
        maybe changed, maybe empty). The robot acts on it when the loop takes it, as
        without the model (so when that is never depends on when the bytes reached the
        loop); its reply leaves no earlier than its arrival (:meth:`outbound`), so the
        program waits the whole way there and back."""
        carried = self.model.carry(data, self.clock.now(), TO_ROBOT)
        self._said(carried, data, TO_ROBOT)
        return carried.data

    def outbound(self, data: bytes, deliver: Callable[[bytes], None]) -> None:
        """A reply toward the program: ``deliver`` what arrives (maybe nothing) when it
        arrives."""
        now = self.clock.now()
        carried = self.model.carry(data, now, TO_PROGRAM)
        self.clock.advance_to(carried.arrives)
        self._said(carried, data, TO_PROGRAM)
        self.hold(carried.arrives - now, lambda: deliver(carried.data))

    def _said(self, carried: Carried, data: bytes, toward: str) -> None:
        """Record a message the link hurt (lost bytes, flipped bits, a dropout)."""
        if carried.dropout:
            self.emit("link-dropout", float(len(data)), f"{toward}: {data[:40]!r} lost whole")
        elif carried.lost or carried.corrupted:
            detail = f"{toward}: {data[:40]!r} -> {carried.data[:40]!r}"
            value = float(carried.lost or carried.corrupted)
            self.emit("link-lost" if carried.lost else "link-corrupted", value, detail)


class Wire:
    """One connection's way back to the program: what is sent goes out in the order it was
    given, a reply over the link when the link delivers it (:meth:`reply`), the simulator's
    own answers (a clock message's, ``?``) untouched but never ahead of a reply held before
    them (:meth:`direct`). Without a link, both just ``send``."""

    def __init__(self, link: Link | None, send: Callable[[bytes], None]) -> None:
        self.link = link
        self.send = send
        self._queue: deque[list[Any]] = deque()

    def reply(self, data: bytes) -> None:
        """A reply over the robot's link."""
        if self.link is None:
            self.send(data)
            return
        entry: list[Any] = [b"", False]
        self._queue.append(entry)
        self.link.outbound(data, lambda got: self._arrived(entry, got))

    def direct(self, data: bytes) -> None:
        """An answer that is not on the robot's link, after whatever is held."""
        if not self._queue:
            self.send(data)
            return
        self._queue.append([data, True])

    def _arrived(self, entry: list[Any], data: bytes) -> None:
        entry[0], entry[1] = data, True
        while self._queue and self._queue[0][1]:
            got = self._queue.popleft()[0]
            self.send(got)
