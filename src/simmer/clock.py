"""The two clocks a :class:`~simmer.runner.Runner` can keep: everything that differs between
a run in real time and a run in lockstep lives here, behind one small interface, so the runner
reads as one loop (as pymunk keeps time in ``Space.step(dt)``).

* :class:`RealTimeClock`: the wall clock paces the steps; clock messages wait for simulated
  time (``!sleep S`` answers once S simulated seconds have passed, ``!idle`` once no drive
  moves, ``!time`` at once).
* :class:`LockstepClock`: the wall clock decides nothing; the simulation advances only when a
  control program asks (its clock messages, see :mod:`simmer.lockstep`) and by the link delay
  after each message it sends, so the same program gives the same run at any speed and on any
  machine.

Both count the bytes of a program's messages taken (answered by the loop, or read and set
aside by a transport): a clock message's `` @N`` waits on that count in either clock
(docs/protocol.md). Transports report bytes they set aside to the clock they are given
(:meth:`Clock.took`); only this module keeps the count.
"""

from __future__ import annotations

import heapq
import math
import threading
from collections.abc import Callable
from dataclasses import dataclass
from typing import Protocol

from simmer.lockstep import FREE_TIME_READS
from simmer.protocol import ClockMessage
from simmer.transport.bus import Request
from simmer.world import Simulation
from simmer.world.events import RunEvent

__all__ = [
    "EPSILON",
    "IDLE_LIMIT",
    "Clock",
    "LockstepClock",
    "RealTimeClock",
    "Wait",
    "make_clock",
]

IDLE_LIMIT = 600.0
"""Longest ``!idle`` wait, in simulated seconds (a drive that never finishes cannot hang it)."""
EPSILON = 1e-9


@dataclass
class Wait:
    """A clock message waiting for simulated time: until ``until`` (seconds) or, with
    ``until`` None, until no drive moves (at most until ``deadline``)."""

    request: Request
    until: float | None
    deadline: float = math.inf
    counts: bool = False
    """Answer with the counts too (the message's `` +``, :meth:`_Counted.answer`)."""


class Clock(Protocol):
    """What the runner asks of its clock (see the module doc)."""

    @property
    def answers_at_once(self) -> bool:
        """Whether a message may be answered in a socket's callback, as soon as it arrives
        (real time), rather than one at a time between steps (lockstep)."""
        ...

    @property
    def link_delay(self) -> float:
        """Simulated seconds each message costs."""
        ...

    @property
    def taken(self) -> int:
        """Bytes of a program's messages taken so far (see :meth:`took`)."""
        ...

    @property
    def waiting(self) -> bool:
        """Whether a clock message waits for simulated time."""
        ...

    def took(self, size: int) -> None:
        """Count ``size`` bytes of a program's messages as taken (any thread)."""
        ...

    def gave(self, size: int) -> None:
        """Count ``size`` bytes sent to the clients (any thread)."""
        ...

    def owes(self, count: Callable[[], int]) -> None:
        """``count()`` says how many replies wait to be collected (a two-port server's)."""
        ...

    def message(self, size: int) -> None:
        """A message of ``size`` bytes (not a clock or localization one) is being answered."""
        ...

    def now(self) -> float:
        """The program's simulated time: when what it sends now leaves it (the link model's
        clock, :class:`simmer.transport.link.Link`)."""
        ...

    def advance_to(self, when: float) -> None:
        """The program cannot go on before simulated time ``when`` (a reply on the link
        model arrives then)."""
        ...

    def at(self, when: float, callback: Callable[[], None]) -> None:
        """Loop thread: call ``callback()`` once simulated time reaches ``when`` (a reply
        the link model holds back until it arrives)."""
        ...

    def start(self, request: Request, clock: ClockMessage) -> None:
        """Act on a clock message now: answer it, or keep it until its time comes."""
        ...

    def holding(self) -> bool:
        """Whether clock messages held for their `` @N`` bytes must wait for the simulation
        to catch up first (lockstep), so when one is acted on never depends on whether the
        bytes before it arrived before or after it."""
        ...

    def due(self) -> bool:
        """Whether the loop may step now as far as the clock is concerned."""
        ...

    def settle(self) -> None:
        """Answer the clock messages whose time has come."""
        ...

    def finish(self, until: float | None) -> None:
        """The run is stopping (its program exited, or a stop): take the steps the messages
        already answered cost, but not past ``until``, so how a run ends never depends on
        whether the loop had taken them before the stop came."""
        ...


class _Counted:
    """The byte count and the waits both clocks keep."""

    def __init__(self, sim: Simulation) -> None:
        self.sim = sim
        self.waits: list[Wait] = []
        self._taken = 0
        self._lock = threading.Lock()
        self.sent = 0
        """Bytes sent to the clients so far (:meth:`gave`)."""
        self._owed: list[Callable[[], int]] = []
        self._timers: list[tuple[float, int, Callable[[], None]]] = []
        self._order = 0

    def at(self, when: float, callback: Callable[[], None]) -> None:
        """Call ``callback()`` once simulated time reaches ``when`` (loop thread), in the
        order asked among those due together."""
        self._order += 1
        heapq.heappush(self._timers, (when, self._order, callback))

    def fire(self) -> None:
        """Call the callbacks whose simulated time has come."""
        timers = self._timers
        while timers and timers[0][0] <= self.sim.time + EPSILON:
            heapq.heappop(timers)[2]()

    @property
    def taken(self) -> int:
        """Bytes of a program's messages taken so far."""
        return self._taken

    @property
    def waiting(self) -> bool:
        """Whether a clock message waits for simulated time."""
        return bool(self.waits)

    def took(self, size: int) -> None:
        """Count ``size`` bytes as taken (a transport's thread may call it)."""
        if size > 0:
            with self._lock:
                self._taken += size

    def gave(self, size: int) -> None:
        """Count ``size`` bytes sent to the clients (a transport's thread may call it)."""
        if size > 0:
            with self._lock:
                self.sent += size

    def owes(self, count: Callable[[], int]) -> None:
        """Add ``count`` to what says how many replies wait to be collected."""
        self._owed.append(count)

    def answer(self, request: Request, value: float, counts: bool) -> None:
        """Answer a clock message with the time ``value``; with ``counts``, also the bytes
        sent to the clients so far and the replies waiting to be collected (the shim's
        `` +``: whether a reply is still on its way to the program)."""
        if counts:
            owed = sum(count() for count in self._owed)
            request.future.set_result([value, float(self.sent), float(owed)])
        else:
            request.future.set_result([value])

    def moving(self, wait: Wait) -> bool:
        """Whether an ``!idle`` wait still waits: a drive moves and its deadline is ahead."""
        return self.sim.robot.any_drive_moving and self.sim.time < wait.deadline - EPSILON

    def emit(self, clock: ClockMessage) -> None:
        """Record the clock message in the run's events, if anyone listens (not a ``!peek``:
        a library's read changes nothing, and how many a library makes is its own business)."""
        sim = self.sim
        if sim.observers and clock.kind != "peek":
            asked = clock.seconds if clock.kind == "sleep" else math.nan
            sim.emit(RunEvent(sim.time, "clock", asked, sim.steps, clock.kind))


class RealTimeClock(_Counted):
    """Simulated time follows the wall clock; clock messages wait for it (module doc)."""

    answers_at_once = True
    link_delay = 0.0
    """A message costs no simulated time in real time."""

    def message(self, size: int) -> None:
        """Count the message's bytes; in real time a message costs no simulated time."""
        self.took(size)

    def now(self) -> float:
        """The simulation's time: the wall clock paces it."""
        return self.sim.time

    def advance_to(self, when: float) -> None:
        """Nothing: the wall clock paces the run (the link holds its replies back itself)."""

    def start(self, request: Request, clock: ClockMessage) -> None:
        """``!sleep``/``!idle`` wait for simulated time; ``!time``/``!sync`` answer now."""
        self.emit(clock)
        sim = self.sim
        if clock.kind == "sleep":
            self.waits.append(Wait(request, sim.time + clock.seconds, counts=clock.counts))
        elif clock.kind == "idle":
            self.waits.append(Wait(request, None, sim.time + IDLE_LIMIT, clock.counts))
        else:
            self.answer(request, sim.time, clock.counts)

    def holding(self) -> bool:
        """Never: the wall clock steps the simulation whatever is held."""
        return False

    def due(self) -> bool:
        """Always: the wall clock paces the steps."""
        return True

    def finish(self, until: float | None) -> None:
        """Nothing: in real time a message costs no simulated time."""

    def settle(self) -> None:
        """Call what waits for simulated time (:meth:`at`), answer each wait whose simulated
        time has passed with the simulated time."""
        if self._timers:
            self.fire()
        if not self.waits:
            return
        sim = self.sim
        waiting = []
        for wait in self.waits:
            done = not self.moving(wait) if wait.until is None else sim.time >= wait.until - EPSILON
            if done:
                self.answer(wait.request, sim.time, wait.counts)
            else:
                waiting.append(wait)
        self.waits = waiting


class LockstepClock(_Counted):
    """The program's clock: the simulation steps only until it would pass it (module doc).

    ``link_delay``: simulated seconds each message costs (default one step, as the
    original's loop, which took in messages once per frame)."""

    answers_at_once = False

    def __init__(self, sim: Simulation, link_delay: float | None = None) -> None:
        super().__init__(sim)
        self.link_delay = sim.dt if link_delay is None else link_delay
        if not (math.isfinite(self.link_delay) and self.link_delay >= 0):
            raise ValueError(f"link_delay must be 0 or more seconds, not {link_delay!r}")
        self.time = sim.time
        """The program's clock; the simulation steps until it would pass it."""
        self._reads = 0

    def message(self, size: int) -> None:
        """A message costs the link delay and ends a run of free clock reads."""
        self.time = max(self.time, self.sim.time) + self.link_delay
        self._reads = 0
        self.took(size)

    def now(self) -> float:
        """The program's clock (the simulation is never ahead of it but by a step)."""
        return max(self.time, self.sim.time)

    def advance_to(self, when: float) -> None:
        """Move the program's clock to ``when`` if it is behind: the simulation steps there
        before the loop takes the next message."""
        self.time = max(self.time, when)

    def start(self, request: Request, clock: ClockMessage) -> None:
        """Advance the program's clock as the message asks and wait until the simulation is
        there: ``!sleep S`` by S, ``!idle`` until no drive moves, a read by nothing (but the
        :data:`~simmer.lockstep.FREE_TIME_READS`-th in a row by one step; ``!peek`` and
        ``!sync`` never)."""
        self.emit(clock)
        sim = self.sim
        self.time = max(self.time, sim.time)
        if clock.kind == "idle":
            self._reads = 0
            self.waits.append(Wait(request, None, sim.time + IDLE_LIMIT, clock.counts))
            return
        if clock.kind == "sleep" and clock.seconds > 0:
            self._reads = 0
            self.time += clock.seconds
        elif clock.kind not in ("sync", "peek"):  # a read (or sleep(0)): free unless waited on
            self._reads += 1
            if self._reads > FREE_TIME_READS:
                self._reads = 0
                self.time += sim.dt
        self.waits.append(Wait(request, self.time, counts=clock.counts))

    def holding(self) -> bool:
        """While the simulation has not caught up with the clock."""
        return self.behind()

    def due(self) -> bool:
        """Only while the simulation is behind the clock or an ``!idle`` wait."""
        return self.behind()

    def finish(self, until: float | None) -> None:
        """Step to the program's clock as the link delay of its last message set it; not
        while a clock message waits (a thread of the program that was sleeping when it
        exited: its sleep is not the run's to finish), nor past ``until``."""
        sim = self.sim
        if self.waits:
            return
        limit = math.inf if until is None else until - EPSILON
        while (sim.steps + 1) * sim.dt <= self.time + EPSILON and sim.time < limit:
            sim.step()

    def behind(self) -> bool:
        """Whether the simulation must step to catch up with the clock or a wait."""
        sim = self.sim
        if (sim.steps + 1) * sim.dt <= self.time + EPSILON:
            return True
        return any(w.until is None and self.moving(w) for w in self.waits)

    def catch_up(self) -> None:
        """Step until the clock and every clock message are met.

        While only ``!idle`` waits keep it stepping, it steps without looking at the waits
        until no drive moves or the first one's deadline passes (what :meth:`behind` would
        decide step by step, at a fraction of the cost: a policy's run is mostly this)."""
        sim = self.sim
        robot = sim.robot
        while self.behind():
            if (sim.steps + 1) * sim.dt <= self.time + EPSILON:
                sim.step()
            else:
                deadline = min(w.deadline for w in self.waits if w.until is None) - EPSILON
                while robot.any_drive_moving and sim.time < deadline:
                    sim.step()
            self.settle()
        self.settle()

    def settle(self) -> None:
        """Call what waits for simulated time (:meth:`at`), answer each wait the simulation
        has reached with the program's clock."""
        if self._timers:
            self.fire()
        if not self.waits:
            return
        sim = self.sim
        waiting = []
        for wait in self.waits:
            if wait.until is None:
                done = not self.moving(wait)
                if done:
                    self.time = max(self.time, sim.time)
                value = self.time
            else:
                done = (sim.steps + 1) * sim.dt > wait.until + EPSILON
                value = wait.until
            if done:
                self.answer(wait.request, value, wait.counts)
            else:
                waiting.append(wait)
        self.waits = waiting


def make_clock(
    sim: Simulation, *, lockstep: bool = False, link_delay: float | None = None
) -> RealTimeClock | LockstepClock:
    """The clock a run of ``sim`` keeps: lockstep (each message costing ``link_delay``
    simulated seconds, default one step) or real time."""
    return LockstepClock(sim, link_delay) if lockstep else RealTimeClock(sim)
