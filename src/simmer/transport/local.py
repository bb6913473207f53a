"""A client link to a simulation in this process, on the lockstep clock (no sockets).

``Client(LocalLink(sim), lockstep=True)`` gives a control program written against
:mod:`simmer.client` the same run it gets from ``simmer run --program``: each message costs
the link delay, ``sleep`` and ``wait_idle`` advance the clock, all through the same
:class:`~simmer.runner.Runner` code. Sweeps, tests and notebooks use it to run a program
without a server.
"""

from __future__ import annotations

from simmer.protocol import CLOCK_PREFIX, Decoded
from simmer.runner import Runner
from simmer.transport.bus import Request
from simmer.world import Simulation


class LocalLink:
    """Messages go straight to a lockstep :class:`Runner` of ``sim`` in this thread."""

    last_text: str | None = None

    def __init__(self, sim: Simulation, link_delay: float | None = None) -> None:
        self.runner = Runner(sim, speed=None, lockstep=True, link_delay=link_delay)

    def exchange(self, message: str) -> list[float]:
        """Execute one message (or clock message) and let the time it costs pass."""
        clock = message.encode("utf-8").startswith(CLOCK_PREFIX)
        request = Request(Decoded(message, message.count(",") + 1, clock=clock), "local")
        self.runner.handle(request)
        self.runner.catch_up()
        return request.future.result()

    def ask(self, message: str) -> tuple[list[float], str | None]:
        """A localization message (``%maze``, ``%show``, ``%pose``): its values, or its text;
        it costs no simulated time."""
        request = Request(Decoded(message, 1, meta=True), "local")
        self.runner.handle(request)
        return request.future.result(), (request.answer[0] if request.answer else None)

    def clock(self, message: str) -> float:
        """Send a clock message; the simulated time after it."""
        (value,) = self.exchange(message)
        return value

    def close(self) -> None:
        """Nothing to release."""
