"""``simmer run``: serve every transport and run the loop, with the window or headless.

Kept out of ``cli.py`` so the window, the headless run and the tests share one path.
"""

from __future__ import annotations

import logging
from collections.abc import Callable
from pathlib import Path

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
    Ctrl-C) or ``seconds`` of simulated time pass, with a window or headless.

    Raises ``OSError`` if a port cannot be opened and :class:`~simmer.errors.SimmerError` if
    no window can be opened. Returns the runner (its history, for callers and tests).
    """
    runner = Runner(sim, speed=speed)
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
    try:
        with link:
            for line in link.describe():
                echo(line)
            if window:
                from simmer.ui import run_window

                echo("window open (press h for help)")
                run_window(runner, until=seconds)
            else:
                pace = "as fast as possible" if speed is None else f"{speed:g}x real time"
                echo(f"running headless, {pace}; Ctrl-C to stop")
                runner.run(until=seconds)
    except KeyboardInterrupt:
        echo("stopped")
    finally:
        runner.bus.close()
    return runner
