"""Lockstep benchmark: what the clock costs a control program started by ``simmer run
--program``, per message and for a whole stock program.

Run ``python benchmarks/bench_lockstep.py`` (or ``python benchmarks/run.py``). Each figure is
the median wall time of several runs on this machine, each run a fresh program process:

* the stock two-port program: the original's ``dead_reckoning.py`` idea (a connection per
  message, send, sleep 0.1 s, read) on the Lab 1 rover with the lab's drive error, as
  ``tests/fixtures/students/two_port_program.py`` writes it;
* per message: a program sending 300 messages, minus a program that sends none, divided by
  300; over the two-port scheme (send, then read at once, a new connection each) and over the
  persistent protocol (``simmer.client``).
"""

from __future__ import annotations

import contextlib
import os
import statistics
import sys
import tempfile
import time
from collections.abc import Iterator
from pathlib import Path

from simmer import Simulation
from simmer.options import RunOptions
from simmer.serve import serve
from simmer.sweep import build_config

ROOT = Path(__file__).resolve().parent.parent
LAB1 = ROOT / "examples" / "lab1_rover.toml"
STUDENT = ROOT / "tests" / "fixtures" / "students" / "two_port_program.py"
MESSAGES = 300
TARGETS = {"stock_s": 0.9}
"""The stock program's run before issue 17's clock took 0.9 s; it must not get slower."""

PROGRAMS = {
    "nothing": "import socket, struct, time\n",
    "two_port": """
import socket, struct, time
for _ in range({n}):
    with socket.socket() as s:
        s.connect(('127.0.0.1', 61200))
        s.send(b'u0')
    with socket.socket() as s2:
        s2.connect(('127.0.0.1', 61201))
        struct.unpack('<f', s2.recv(1024))
""",
    "stream": """
from simmer.client import connect
with connect() as robot:
    for _ in range({n}):
        robot.read('u0')
""",
}


@contextlib.contextmanager
def quiet() -> Iterator[None]:
    """Send what the programs print (to this process's standard output) to nowhere."""
    sys.stdout.flush()
    saved = os.dup(1)
    with open(os.devnull, "wb") as nowhere:
        os.dup2(nowhere.fileno(), 1)
    try:
        yield
    finally:
        os.dup2(saved, 1)
        os.close(saved)


def run_seconds(command: str, sim: Simulation) -> float:
    """Wall seconds of one ``--program`` run on the lockstep clock (the program must succeed)."""
    started = time.perf_counter()
    with quiet():
        served = serve(
            sim,
            RunOptions.free_ports(speed=None, program=command, timeout=120, clock="lockstep"),
            echo=lambda _line: None,
        )
    seconds = time.perf_counter() - started
    if served.exit_status != 0:
        raise SystemExit(f"the benchmark program {command!r} failed")
    return seconds


def median_seconds(command: str, repeats: int = 7) -> float:
    """Median over ``repeats`` runs, after one warm-up run."""
    config = build_config(str(LAB1), (("drives.w0.error", {"x": 0.02, "y": 0.05, "rotation": 1}),))
    run_seconds(command, Simulation(config, seed=3))
    return statistics.median(
        run_seconds(command, Simulation(config, seed=3)) for _ in range(repeats)
    )


def main() -> dict[str, float]:
    """Run the lockstep benchmark and print its figures."""
    figures: dict[str, float] = {}
    with tempfile.TemporaryDirectory() as folder:
        for name, code in PROGRAMS.items():
            path = Path(folder) / f"{name}.py"
            path.write_text(code.format(n=MESSAGES), encoding="utf-8")
            figures[name] = median_seconds(f"{sys.executable} {path}")
    figures["stock_s"] = median_seconds(f"{sys.executable} {STUDENT} dead_reckoning 1.1")
    for name in ("two_port", "stream"):
        figures[f"{name}_ms"] = (figures[name] - figures["nothing"]) / MESSAGES * 1000
    rows = [
        ("stock two-port program (send, sleep 0.1 s, read), s per run", "stock_s", "<= 0.9"),
        ("two-port message (send, read at once), ms per message", "two_port_ms", ""),
        ("persistent-protocol message (simmer.client), ms per message", "stream_ms", ""),
        ("a program that sends nothing, s per run", "nothing", ""),
    ]
    print("SimMeR lockstep benchmark")
    for label, key, target in rows:
        value = figures[key]
        verdict = ""
        if key in TARGETS:
            verdict = "ok" if value <= TARGETS[key] else "MISSED"
        print(f"  {label:<72} {value:10.3f}  {target:>6} {verdict}")
    return figures


if __name__ == "__main__":
    main()
