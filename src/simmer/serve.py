"""``simmer run --headless``: serve every transport and run the loop until Ctrl-C or a time limit.

Kept out of ``cli.py`` so the window (which shares the :class:`~simmer.runner.Runner`) and the
tests can use the same pieces.
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


def run_headless(
    sim: Simulation,
    *,
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
    """Serve and step ``sim`` until Ctrl-C or ``seconds`` of simulated time; returns the runner."""
    runner = Runner(sim, speed=speed)
    link = Link(
        runner.bus,
        sim.config.settings,
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
        pace = "as fast as possible" if speed is None else f"{speed:g}x real time"
        echo(f"running headless, {pace}; Ctrl-C to stop")
        try:
            runner.run(until=seconds)
        except KeyboardInterrupt:
            echo("stopped")
        finally:
            runner.bus.close()
    return runner
