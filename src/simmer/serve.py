"""``simmer run``: serve every transport and run the loop, with the window or headless.

Kept out of ``cli.py`` so the window, the headless run and the tests share one path.
"""

from __future__ import annotations

import logging
import signal
import threading
from collections.abc import Callable
from pathlib import Path
from types import FrameType

from simmer.runner import Runner
from simmer.transport import STREAM_PORT, Link
from simmer.world import Simulation

log = logging.getLogger("simmer.serve")


def parse_speed(text: str) -> float | None:
    """``"max"`` -> None (as fast as possible); otherwise a positive multiple of real time."""
    if text.strip().lower() == "max":
        return None
    try:
        value = float(text)
    except ValueError:
        raise ValueError(f"speed is a number (1 = real time) or 'max', not {text!r}") from None
    if not value > 0 or value == float("inf"):
        raise ValueError(f"speed must be more than 0, not {text!r}")
    return value


STOP_SIGNALS = ("SIGTERM", "SIGHUP")
"""Signals that stop a run as Ctrl-C does (``kill``, closing the terminal), where they exist."""


def _stop_on_signals() -> Callable[[], None]:
    """Make :data:`STOP_SIGNALS` raise :class:`KeyboardInterrupt` in the main thread, so a run
    ends through the same cleanup as Ctrl-C (serial link removed, ports closed) instead of
    dying at once; a second signal during that cleanup is ignored. Returns what puts the
    previous handlers back. Off the main thread (tests) nothing changes: only the main thread
    may install handlers."""
    if threading.current_thread() is not threading.main_thread():
        return lambda: None
    stopping = False

    def stop(signum: int, _frame: FrameType | None) -> None:
        nonlocal stopping
        if not stopping:
            stopping = True
            raise KeyboardInterrupt(signal.Signals(signum).name)

    previous = {}
    for name in STOP_SIGNALS:
        if (number := getattr(signal, name, None)) is not None:
            previous[number] = signal.signal(number, stop)

    def restore() -> None:
        for number, handler in previous.items():
            signal.signal(number, handler)

    return restore


def serve(
    sim: Simulation,
    *,
    window: bool,
    speed: float | None = 1.0,
    seconds: float | None = None,
    host: str | None = None,
    port_rx: int | None = None,
    port_tx: int | None = None,
    stream_port: int = STREAM_PORT,
    serial: bool = False,
    serial_link: Path | None = None,
    echo: Callable[[str], None] = print,
) -> Runner:
    """Serve every transport and run ``sim`` until the user quits (Esc, closing the window,
    Ctrl-C, SIGTERM, SIGHUP) or ``seconds`` of simulated time pass, with a window or headless.

    Raises ``OSError`` if a port cannot be opened and :class:`~simmer.errors.SimmerError` if
    no window can be opened or something is already at ``serial_link``. Returns the runner
    (its history, for callers and tests).
    """
    runner = Runner(sim, speed=speed)
    restore_signals = _stop_on_signals()
    try:
        link = Link(
            runner.bus,
            sim.config,
            host=host,
            port_rx=port_rx,
            port_tx=port_tx,
            stream_port=stream_port,
            serial=serial,
            serial_link=serial_link,
        )
        with link:
            for line in link.describe():
                echo(line)
            if window:
                from simmer.ui import run_window

                run_window(runner, until=seconds, echo=echo)
            else:
                pace = "as fast as possible" if speed is None else f"{speed:g}x real time"
                echo(f"running headless, {pace}; Ctrl-C to stop")
                runner.run(until=seconds)
    except KeyboardInterrupt:
        echo("stopped")
    finally:
        runner.bus.close()
        restore_signals()
    return runner
