"""Helpers for the control-link tests: a live simulator on free loopback ports."""

from __future__ import annotations

import signal
import socket
import struct
import subprocess
import sys
import threading
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

from simmer.options import RunOptions
from simmer.protocol import FRAME_HEADER
from simmer.runner import Runner
from simmer.serve import Served, serve
from simmer.transport import Transports
from simmer.world import Simulation

from helpers import wait_for

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
    link = Transports(runner.bus, sim.config, options, clock=runner.clock)
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


def _exactly(sock: socket.socket, size: int) -> bytes:
    """``size`` bytes from ``sock`` (the server must not close it before)."""
    data = b""
    while len(data) < size:
        chunk = sock.recv(size - len(data))
        assert chunk, "connection closed mid-frame"
        data += chunk
    return data


def read_frame(sock: socket.socket) -> list[float]:
    """Read one persistent-protocol reply frame."""
    width, count = FRAME_HEADER.unpack(_exactly(sock, FRAME_HEADER.size))
    code = "<f" if width == 4 else "<d"
    return [value for (value,) in struct.iter_unpack(code, _exactly(sock, width * count))]


def stream(port: int) -> socket.socket:
    """A persistent-protocol connection to ``port`` (no Nagle delay)."""
    sock = socket.create_connection(("127.0.0.1", port), timeout=10)
    sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
    return sock


def closed_by_server(sock: socket.socket) -> bool:
    """True once the server has closed ``sock`` (whatever it sent before is read and dropped)."""
    try:
        while sock.recv(65536):
            pass
    except ConnectionResetError:
        pass
    return True


@contextmanager
def loop(runner: Runner) -> Iterator[None]:
    """Run ``runner`` in a thread until the block ends."""
    stop = threading.Event()
    thread = threading.Thread(target=runner.run, kwargs={"stop_event": stop})
    thread.start()
    try:
        yield
    finally:
        stop.set()
        thread.join()
        runner.bus.close()


def launch(tmp_path: Path, *args: str, nofile: int | None = None) -> subprocess.Popen[bytes]:
    """``simmer run --headless`` on free ports in a subprocess, output in ``tmp_path``; waits
    until it serves."""
    limit = f"import resource; resource.setrlimit(resource.RLIMIT_NOFILE, ({nofile}, {nofile}))"
    code = "\n".join(
        [
            "import sys",
            limit if nofile else "",
            "from simmer.cli import main",
            "sys.argv = ['simmer', *sys.argv[1:]]",
            "main()",
        ]
    )
    argv = ["run", "--headless", "--port", "0", "--port-rx", "0", "--port-tx", "0", *args]
    with (tmp_path / "out").open("wb") as out, (tmp_path / "err").open("wb") as err:
        proc = subprocess.Popen([sys.executable, "-c", code, *argv], stdout=out, stderr=err)
    wait_for(lambda: "running headless" in output(tmp_path), "simmer run to start", 60)
    return proc


def output(tmp_path: Path, name: str = "out") -> str:
    """What a process :func:`launch` started has written so far to ``name`` (out or err)."""
    return (tmp_path / name).read_text(errors="replace")


def stream_port_of(tmp_path: Path) -> int:
    """The persistent port a process :func:`launch` started serves on."""
    line = next(li for li in output(tmp_path).splitlines() if li.startswith("persistent TCP"))
    return int(line.split(" port ")[1].split()[0])


def stop(proc: subprocess.Popen[bytes], how: int = signal.SIGTERM) -> int:
    """Signal ``proc`` to stop; its exit status (it is killed if it takes over 30 s)."""
    proc.send_signal(how)
    try:
        return proc.wait(timeout=30)
    except subprocess.TimeoutExpired:
        proc.kill()
        proc.wait()
        raise


def free_port() -> int:
    """A TCP port nothing listens on right now."""
    with socket.create_server(("127.0.0.1", 0)) as sock:
        port: int = sock.getsockname()[1]
    return port


def read_text_frame(sock: socket.socket) -> str:
    """One persistent-protocol text frame (width 0: ``?``'s reasons, ``%maze``) from ``sock``."""
    width, size = FRAME_HEADER.unpack(_exactly(sock, FRAME_HEADER.size))
    assert width == 0
    return _exactly(sock, size).decode()
