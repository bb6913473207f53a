"""Helpers for the control-link tests: a live simulator on free loopback ports."""

from __future__ import annotations

import socket
import struct
import threading
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

from simmer.options import RunOptions
from simmer.runner import Runner
from simmer.serve import Served, serve
from simmer.transport import Transports
from simmer.world import Simulation

LONG_SILENCE = 60.0
"""A serial port's silence (s) that a test's pause is certain to be shorter than."""


@contextmanager
def serving(
    sim: Simulation | None = None,
    *,
    speed: float | None = 1.0,
    serial: bool = False,
    serial_link: Path | None = None,
    silence: float | None = None,
) -> Iterator[tuple[Runner, Transports]]:
    """Run a simulation (default: the built-in one) in a loop thread, serving every transport
    on free ports (``silence``: the serial port's, if not the Arduino's); everything is stopped
    and closed on exit."""
    sim = sim if sim is not None else Simulation.from_config()
    runner = Runner(sim, speed=speed)
    stop = threading.Event()
    options = RunOptions.free_ports(serial=serial, serial_link=serial_link)
    link = Transports(runner.bus, sim.config, options)
    if link.serial is not None and silence is not None:
        link.serial.silence = silence
    thread = threading.Thread(target=runner.run, kwargs={"stop_event": stop})
    with link:
        thread.start()
        try:
            yield runner, link
        finally:
            stop.set()
            thread.join()
            runner.bus.close()


def run_program(
    sim: Simulation,
    command: str,
    *,
    echo: Callable[[str], None] = lambda _line: None,
    **options: Any,
) -> Served:
    """``simmer run --headless --program COMMAND``: on free ports, the lockstep clock, as fast
    as it goes, with a 120 s wall limit unless ``options`` say otherwise."""
    settings = {"speed": None, "clock": "lockstep", "timeout": 120} | options
    return serve(sim, RunOptions.free_ports(program=command, **settings), echo=echo)


def two_port_raw(link: Transports, message: bytes) -> bytes:
    """The original clients' way: send on port_rx and close, then read port_tx to the end."""
    with socket.create_connection(("127.0.0.1", link.two_port.port_rx)) as out:
        out.sendall(message)
    return two_port_collect(link)


def two_port_collect(link: Transports) -> bytes:
    """Connect to port_tx and read what it sends, to the end."""
    data = b""
    with socket.create_connection(("127.0.0.1", link.two_port.port_tx), timeout=10) as back:
        while chunk := back.recv(1024):
            data += chunk
    return data


def unpack(data: bytes, width: int = 4) -> list[float]:
    """Packed replies as floats of ``width`` bytes."""
    code = "<f" if width == 4 else "<d"
    return [value for (value,) in struct.iter_unpack(code, data)]


def two_port_send(link: Transports, message: bytes, width: int = 4) -> list[float]:
    """:func:`two_port_raw`, the reply unpacked as floats of ``width`` bytes."""
    return unpack(two_port_raw(link, message), width)


def read_frame(sock: socket.socket) -> list[float]:
    """Read one persistent-protocol reply frame."""

    def exactly(size: int) -> bytes:
        data = b""
        while len(data) < size:
            chunk = sock.recv(size - len(data))
            assert chunk, "connection closed mid-frame"
            data += chunk
        return data

    width, count = struct.unpack("<BH", exactly(3))
    code = "<f" if width == 4 else "<d"
    return [value for (value,) in struct.iter_unpack(code, exactly(width * count))]
