"""Soak benchmark: the simulator's resident memory while one client sends many messages.

Run ``python benchmarks/bench_soak.py`` (or ``python benchmarks/run.py``). A persistent-protocol
client sends ``u0,w0-0`` and reads each reply while the loop steps at full speed; the RSS of
this process (the simulator's, the client's socket being negligible) is read after 10,000,
100,000 and 300,000 messages. Nothing is kept per message (the HUD's command log, the run's
history and every queue are bounded), so after the allocator's first growth the RSS stays flat:
the target is 100,000 messages within 2 MB of 10,000.
"""

from __future__ import annotations

import gc
import socket
import threading
from pathlib import Path

from simmer import Simulation
from simmer.options import RunOptions
from simmer.runner import Runner
from simmer.transport.transports import Transports
from simmer.world.outcome import Outcome

MARKS = (10_000, 100_000, 300_000)
TARGET_MB = 2.0


def rss_mb() -> float:
    """This process's resident set in MB."""
    for line in Path("/proc/self/status").read_text(encoding="ascii").splitlines():
        if line.startswith("VmRSS:"):
            return int(line.split()[1]) / 1024
    return float("nan")


def soak() -> dict[int, float]:
    """RSS in MB after each of :data:`MARKS` messages."""
    sim = Simulation.from_config()
    Outcome.attach(sim)
    runner = Runner(sim, speed=None)
    link = Transports(runner.bus, sim.config, RunOptions.free_ports())
    stop = threading.Event()
    loop = threading.Thread(target=runner.run, kwargs={"stop_event": stop})
    found = {}
    with link:
        loop.start()
        try:
            with socket.create_connection(("127.0.0.1", link.stream.port)) as sock:
                sent = 0
                for mark in MARKS:
                    while sent < mark:
                        sock.sendall(b"u0,w0-0\n")
                        width, low, high = sock.recv(3, socket.MSG_WAITALL)
                        sock.recv(width * (low | high << 8), socket.MSG_WAITALL)
                        sent += 1
                    gc.collect()
                    found[mark] = rss_mb()
        finally:
            stop.set()
            loop.join()
            runner.bus.close()
    return found


def main() -> dict[int, float]:
    """Run the soak and print RSS against the target."""
    found = soak()
    growth = found[100_000] - found[10_000]
    print("SimMeR soak benchmark (persistent protocol, loop at full speed)")
    for mark, mb in found.items():
        print(f"  RSS after {mark:>7,} messages, MB{'':<44} {mb:10.2f}")
    verdict = "ok" if growth <= TARGET_MB else "MISSED"
    print(f"  {'growth from 10,000 to 100,000 messages, MB':<72} {growth:10.2f}  <= 2 {verdict}")
    return found


if __name__ == "__main__":
    main()
