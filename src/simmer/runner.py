"""The simulation loop: the one thread that owns a :class:`~simmer.world.Simulation`.

It steps the simulation at ``speed`` times real time (``None``: as fast as it can), answers
every message on its :class:`~simmer.transport.CommandBus` as soon as it arrives (it waits on
the bus, and on the TCP sockets the bus watches, not on a sleep, until the next step is due: a
read is an instant snapshot, a drive starts at the next step), and calls ``on_frame`` at most
~60 times per wall-clock second. The window's hook (:meth:`simmer.ui.bridge.Bridge.sync`) only
applies queued key and mouse actions and publishes an immutable snapshot; the window draws it in
another thread, so drawing never delays a reply.

What time means is its :class:`~simmer.clock.Clock`'s business: in real time the wall clock
paces the steps; on the lockstep clock the simulation advances only when a control program asks
(the persistent protocol's clock messages, see :mod:`simmer.lockstep`) and by ``link_delay``
after each message it sends, so the same program gives the same run at any speed and on any
machine (``speed`` then only paces the steps for a window to watch). The runner only asks the
clock whether it may step, hands it each message and clock message, and lets it settle.
"""

from __future__ import annotations

import logging
import math
import threading
import time
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass

from simmer.clock import EPSILON, Clock, LockstepClock, make_clock
from simmer.localize.messages import Localization
from simmer.protocol import (
    CLOCK_PREFIX,
    ClockMessage,
    ClockText,
    CommandText,
    LocalizationText,
    Refused,
    parse_clock,
    printable,
)
from simmer.transport.bus import CommandBus, Request
from simmer.world import Simulation
from simmer.world.events import RunEvent

log = logging.getLogger("simmer.runner")

FRAME_INTERVAL = 1.0 / 60.0
"""Wall-clock seconds between ``on_frame`` calls (at most)."""
MAX_LAG = 0.25
"""If stepping falls this many wall seconds behind, drop the backlog instead of racing."""
MAX_WAIT = 0.05
"""Longest single wait, so a stop request is noticed promptly."""
MAX_LOGGED = 3
"""Why-NaN lines logged per message; the rest are counted in one more line, so a message of
1,000 bad commands writes four lines, not 1,000."""
LOG_LINES_PER_SECOND = 10
"""Log lines about one client's bad messages per wall-clock second; past it they are counted
and the count is logged once the second is over (a client flooding bad commands writes ten
lines a second, not thousands). A client is its host and transport: a two-port client uses a
new port for every message."""
MAX_LOG_CLIENTS = 1024
"""Clients whose log lines are counted at once (the count starts afresh past it)."""
MAX_REASONS = 20
"""Why-NaN reasons kept per message for the client (the persistent protocol's ``?``)."""

SYNC_WAIT = 5.0
"""Wall seconds a clock message waits for the bytes it says the program sent before it (its
`` @N``) to arrive and be answered. They come within a millisecond on a working link; bytes
that never make a message (a line with no end, a two-port connection left open) would stall
every sleep, so past this the clock goes on, with a warning, and counts them as taken."""

FrameCallback = Callable[["Runner"], bool]


class _LogBudget:
    """Log lines per client, at most :data:`LOG_LINES_PER_SECOND` a second of ``clock`` (wall
    time); the rest are counted and said in one line when that client's second is over."""

    def __init__(self, clock: Callable[[], float] = time.monotonic) -> None:
        self._clock = clock
        self._spent: dict[str, tuple[float, int, int]] = {}  # second started, lines, held back
        self.holding = False
        """Whether some client's lines are held back (:meth:`flush` says how many)."""

    def flush(self) -> None:
        """Say how many lines were held back for each client whose second is over."""
        now = self._clock()
        self.holding = False
        for who, (started, lines, held) in list(self._spent.items()):
            if not held:
                continue
            if now - started < 1.0:
                self.holding = True
                continue
            self._say_held(who, held)
            self._spent[who] = (started, lines, 0)

    @staticmethod
    def _say_held(who: str, held: int) -> None:
        log.warning("%s: %d more log lines in one second, not written", who, held)

    def log(self, client: str, level: int, text: str, *args: object) -> None:
        """Log ``text % args`` about ``client`` (already printable) unless its budget is
        spent."""
        who = client.rsplit(":", 1)[0] if client.startswith(("two-port ", "stream ")) else client
        now = self._clock()
        started, lines, held = self._spent.get(who, (now, 0, 0))
        if now - started >= 1.0:
            if held:
                self._say_held(who, held)
            started, lines, held = now, 0, 0
        if lines < LOG_LINES_PER_SECOND:
            log.log(level, text, *args)
            lines += 1
        else:
            held += 1
            self.holding = True
        if len(self._spent) >= MAX_LOG_CLIENTS and who not in self._spent:
            self._spent.clear()
        self._spent[who] = (started, lines, held)


@dataclass
class _Held:
    """A clock message waiting until ``after`` bytes of the program's messages are taken, or
    the wall-clock ``deadline`` (monotonic)."""

    request: Request
    clock: ClockMessage
    after: int
    deadline: float


class Runner:
    """Drive a simulation in real time (or faster) and serve the bus; see the module doc."""

    def __init__(
        self,
        sim: Simulation,
        *,
        speed: float | None = 1.0,
        bus: CommandBus | None = None,
        lockstep: bool = False,
        link_delay: float | None = None,
        clock: Clock | None = None,
        keep_time: bool = False,
    ) -> None:
        self.sim = sim
        self.keep_time = keep_time
        """In real time, never drop a backlog of steps (:data:`MAX_LAG`): a loop held up
        (a loaded machine) catches up, stepping before it answers again, so the simulation's
        clock stays the wall clock, as a real robot's does (the ground-truth robot behind
        ``simmer tap``: a reading's time on the tap's clock is the robot's)."""
        self.bus = bus if bus is not None else CommandBus()
        self._paused = False
        self._speed: float | None = None
        self._reschedule = True
        self.speed = speed
        self.clock: Clock = (
            clock
            if clock is not None
            else make_clock(sim, lockstep=lockstep, link_delay=link_delay)
        )
        """``clock``, else real time or lockstep (``link_delay``: simulated seconds each message
        costs there, default one step); transports report the bytes they set aside to it."""
        self._held: deque[_Held] = deque()
        self._log = _LogBudget()
        self._forgiven = 0
        """Bytes a clock message gave up waiting for (:data:`SYNC_WAIT`), counted as taken."""
        self.over_limit = 0
        """Messages refused whole at a message limit (``MAX_MESSAGE_BYTES``, ``MAX_COMMANDS``)."""
        self.localization = Localization(sim)
        """Answers ``%maze``, ``%show`` and ``%pose``, and keeps their bounds."""

    @property
    def speed(self) -> float | None:
        """Multiple of real time (``None``: as fast as possible). Settable while running."""
        return self._speed

    @speed.setter
    def speed(self, value: float | None) -> None:
        if value is not None and not (math.isfinite(value) and value > 0):
            raise ValueError(f"speed must be a positive number or None (max), not {value!r}")
        self._speed = value
        self._reschedule = True
        if self.sim.observers:
            sim = self.sim
            rate = math.nan if value is None else value
            sim.emit(RunEvent(sim.time, "speed", rate, sim.steps))

    @property
    def paused(self) -> bool:
        """True while the loop does not step (commands are still answered). Settable."""
        return self._paused

    @paused.setter
    def paused(self, value: bool) -> None:
        if value != self._paused and self.sim.observers:
            sim = self.sim
            sim.emit(RunEvent(sim.time, "pause" if value else "resume", 0.0, sim.steps))
        self._paused = value

    @property
    def link_delay(self) -> float:
        """Simulated seconds each message costs (0 in real time)."""
        return self.clock.link_delay

    @property
    def clients(self) -> list[str]:
        """Clients connected right now (from the bus)."""
        return self.bus.clients

    def step_once(self) -> None:
        """Advance one step (e.g. the window's single-step key while paused)."""
        self.sim.step()

    def handle(self, request: Request) -> list[float]:
        """Execute one request on the simulation and fulfil its future. Why its NaN replies are
        NaN is logged (bounded, see :data:`MAX_LOGGED`) and kept in ``request.reasons``. A
        clock message is answered later, when simulated time has got where it asks."""
        match request.decoded:
            case ClockText(text=text):
                self._clock_message(request, text)
                return []
            case LocalizationText(text=text):
                return self._localization(request, text)
            case CommandText(text=text, commands=commands, size=size, dropped=dropped):
                self.clock.message(size)
                if dropped:  # SimMeR v1.2 answered the first frame of a message only
                    client = printable(request.client)
                    self._log.log(
                        client,
                        logging.WARNING,
                        "%s sent more than one frame in a message: the first is answered, "
                        "%r is not (SimMeR v1.2 answers one frame per message: send each "
                        "on its own, or put all the commands in one frame)",
                        client,
                        dropped,
                    )
                replies, failed = self.sim.replies(
                    commands or self.sim.parse(text), text, request.client
                )
                if records := [(a.level, a.why) for a in failed if a.why is not None]:
                    self._report(printable(request.client), records, request.reasons)
            case Refused(error=error, count=count, size=size, over_limit=over):
                self.over_limit += over
                self.clock.message(size)
                error = printable(error)
                client = printable(request.client)
                self._log.log(client, logging.WARNING, "bad message from %s: %s", client, error)
                request.reasons.append(error)
                replies = [math.nan] * count
        request.future.set_result(replies)
        return replies

    def _localization(self, request: Request, text: str) -> list[float]:
        """A localization message (``%maze``, ``%show``, ``%pose``): answered now, at no
        simulated time (no link delay) and touching nothing the simulation answers
        (:mod:`simmer.localize.messages`); a bad one answers NaN, with its reason."""
        self.clock.took(request.decoded.size)
        try:
            replies, answer = self.localization.answer(text, request.client)
        except ValueError as exc:
            client = printable(request.client)
            self._log.log(client, logging.WARNING, "bad message from %s: %s", client, exc)
            request.reasons.append(str(exc))
            replies, answer = [math.nan], None
        if answer is not None:
            request.answer.append(answer)
        request.future.set_result(replies)
        return replies

    # ----------------------------------------------------------------- the clock

    def _clock_message(self, request: Request, text: str) -> None:
        """Take ``!sleep``, ``!idle``, ``!time`` or ``!sync`` (see the module doc); one whose
        `` @N`` says the program sent bytes not yet taken waits for them (:meth:`_release`)."""
        try:
            clock = parse_clock(text)
        except ValueError as exc:
            log.warning("%s: %s", printable(request.client), exc)
            request.reasons.append(str(exc))
            request.future.set_result([math.nan])
            return
        if clock.after is None:  # the program's own clock message, on one of its connections
            self.clock.took(request.decoded.size)
            self.clock.start(request, clock)
            return
        self._held.append(_Held(request, clock, clock.after, time.monotonic() + SYNC_WAIT))
        self._release()

    def _release(self) -> bool:
        """Act on the held clock messages, in order, whose bytes have all been taken (or
        that waited :data:`SYNC_WAIT`); True if any was. Only while the clock does not hold
        them back (:meth:`~simmer.clock.Clock.holding`)."""
        released = False
        while self._held and not self.clock.holding():
            held = self._held[0]
            missing = held.after - self.clock.taken - self._forgiven
            if missing > 0:
                if time.monotonic() < held.deadline:
                    break
                self._forgiven += missing
                log.warning(
                    "%s: %d byte(s) the program wrote before '%s' never arrived as complete "
                    "messages within %g s (a line with no end, a connection left open?); the "
                    "clock goes on without them, so this run may not repeat exactly",
                    printable(held.request.client),
                    missing,
                    held.clock.kind,
                    SYNC_WAIT,
                )
            self._held.popleft()
            self.clock.start(held.request, held.clock)
            released = True
        return released

    def _report(self, client: str, records: list[tuple[int, str]], reasons: list[str]) -> None:
        """Log why the first few NaN answers of one message are NaN (``records``: level and
        why) and count the rest (and no more than the client's budget, :class:`_LogBudget`);
        keep the first :data:`MAX_REASONS` for the client."""
        for level, text in records[:MAX_LOGGED]:
            self._log.log(client, level, "%s: %s", client, text)
        more = sum(level >= logging.WARNING for level, _ in records[MAX_LOGGED:])
        if more:
            self._log.log(
                client,
                logging.WARNING,
                "%s: %d more bad commands in that message, not logged",
                client,
                more,
            )
        reasons.extend(text for _, text in records[:MAX_REASONS])
        if len(records) > MAX_REASONS:
            reasons.append(f"... and {len(records) - MAX_REASONS} more")

    def serve(self, timeout: float = 0.0, limit: int | None = None) -> int:
        """Answer the requests queued once the wait (up to ``timeout`` s) ends; how many.

        Requests queued meanwhile (a client refilling its pipeline as replies go out) wait for
        the next turn, so one busy client cannot keep the others waiting. A request whose
        handling raises gets the exception instead of replies; the loop goes on.
        """
        if self._held and self._release():
            timeout = 0.0
        self.bus.wait(timeout)
        served = 0
        for _ in range(self.bus.queued if limit is None else min(limit, self.bus.queued)):
            request = self.bus.get()
            if request is None:
                break
            self.answer(request)
            served += 1
        if self._held:
            self._release()
        if self._log.holding:
            self._log.flush()
        self.clock.settle()
        return served

    def answer(self, request: Request) -> bool:
        """:meth:`handle` a request; one whose handling raises gets the exception instead of
        replies, and the loop goes on. True if nothing waits for the loop's attention after
        it (a clock message, log lines held back): the bus may go on waiting."""
        try:
            self.handle(request)
        except Exception as exc:
            log.error("answering %s failed: %s", printable(request.client), exc, exc_info=exc)
            if not request.future.done():
                request.future.set_exception(exc)
        return not (self.clock.waiting or self._held or self._log.holding)

    def run(
        self,
        on_frame: FrameCallback | None = None,
        stop_event: threading.Event | None = None,
        until: float | None = None,
    ) -> None:
        """Loop until ``on_frame`` returns False, ``stop_event`` is set, or simulated ``until``.

        It steps while the clock lets it (:meth:`~simmer.clock.Clock.due`). A clock that
        answers at once (real time) has every request answered between two steps, or in the
        socket's callback as it arrives; otherwise (lockstep) the loop takes the next request,
        one at a time, only once the simulation has caught up, so a program's messages meet the
        simulation in the program's order.
        """
        self.sim.own(threading.get_ident())
        if self.clock.answers_at_once:
            self.bus.answer_with(self.answer)
        try:
            self._run(on_frame, stop_event, until)
            if stop_event is not None and stop_event.is_set():
                self.clock.finish(until)
        finally:
            self.bus.answer_with(None)
            self.sim.own(None)

    def _run(
        self,
        on_frame: FrameCallback | None,
        stop_event: threading.Event | None,
        until: float | None,
    ) -> None:
        sim = self.sim
        clock = self.clock
        at_once = clock.answers_at_once
        next_step = next_frame = time.monotonic()
        while not (stop_event is not None and stop_event.is_set()):
            if until is not None and sim.time >= until - EPSILON:
                break
            now = time.monotonic()
            if on_frame is not None and now >= next_frame:
                if not on_frame(self):
                    break
                next_frame = max(next_frame + FRAME_INTERVAL, now)
                now = time.monotonic()
            wake = next_frame if on_frame is not None else math.inf
            if self._reschedule:
                self._reschedule = False
                next_step = now
            speed = self._speed
            if self.paused or not clock.due():
                self.serve(min(wake - now, MAX_WAIT), limit=None if at_once else 1)
                next_step = time.monotonic()
            elif speed is None or now >= next_step:
                behind = speed is not None and now - next_step >= sim.dt / speed
                if at_once and not (behind and self.keep_time):
                    self.serve()
                sim.step()
                clock.settle()
                if speed is not None:
                    next_step += sim.dt / speed
                    if now - next_step > MAX_LAG and not self.keep_time:
                        next_step = now
            elif at_once:
                self.serve(min(next_step - now, wake - now, MAX_WAIT))
            else:  # requests wait until the simulation has caught up with the clock
                self.bus.wait(min(next_step - now, wake - now, MAX_WAIT))


class LocalLink:
    """A client link to a simulation in this process, on the lockstep clock (no sockets):
    messages go straight to a lockstep :class:`Runner` of ``sim`` in this thread.

    ``Client(LocalLink(sim), lockstep=True)`` gives a control program written against
    :mod:`simmer.client` the same run it gets from ``simmer run --program``: each message
    costs the link delay, ``sleep`` and ``wait_idle`` advance the clock, all through the same
    :class:`Runner` code. Sweeps, tests and notebooks use it to run a program without a
    server.
    """

    last_text: str | None = None

    def __init__(self, sim: Simulation, link_delay: float | None = None) -> None:
        self._clock = LockstepClock(sim, link_delay)
        self.runner = Runner(sim, speed=None, clock=self._clock)

    def exchange(self, message: str) -> list[float]:
        """Execute one message (or clock message) and let the time it costs pass."""
        if message.encode("utf-8").startswith(CLOCK_PREFIX):
            request = Request(ClockText(message), "local")
        else:
            request = Request(CommandText(message, message.count(",") + 1), "local")
        self.runner.handle(request)
        self._clock.catch_up()
        return request.future.result()

    def ask(self, message: str) -> tuple[list[float], str | None]:
        """A localization message (``%maze``, ``%show``, ``%pose``): its values, or its text;
        it costs no simulated time."""
        request = Request(LocalizationText(message), "local")
        self.runner.handle(request)
        return request.future.result(), (request.answer[0] if request.answer else None)

    def clock(self, message: str) -> float:
        """Send a clock message; the simulated time after it."""
        (value,) = self.exchange(message)
        return value

    def close(self) -> None:
        """Nothing to release."""
