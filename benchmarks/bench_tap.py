"""``simmer tap`` benchmark: the round-trip time a tap adds between a program and a robot.

Each robot is a simulator serving its serial port in a process of its own (as ``simmer run
--serial`` would); a pyserial client sends ``u0`` and reads its 4-byte reply, ``--queries`` times
straight on one robot's port, and as many times through ``simmer tap`` (a process of its own,
recording) on a second robot's, in turns so that load on the machine falls on both alike. It
prints the median and 95th percentile of each, what the tap adds, and the tap's own CPU time
per exchange (the figure load does not swing).

Run standalone: ``.venv/bin/python benchmarks/bench_tap.py [--queries N]``. ``main()`` returns
the rows for ``benchmarks/run.py``.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

import serial

SERVER = """
import json, sys, threading
from simmer.options import RunOptions
from simmer.runner import Runner
from simmer.transport import Transports
from simmer.world import Simulation
sim = Simulation.from_config()
runner = Runner(sim, speed=1.0)
with Transports(runner.bus, sim.config, RunOptions.free_ports(serial=True)) as link:
    print(json.dumps({"serial": link.serial.path}), flush=True)
    stop = threading.Event()
    threading.Thread(target=lambda: (sys.stdin.read(), stop.set()), daemon=True).start()
    runner.run(stop_event=stop)
    runner.bus.close()
"""
CONFIG = Path(__file__).resolve().parent.parent / "examples" / "simmer_default.toml"


def round_trips(path: str, count: int) -> list[float]:
    """Milliseconds of each of ``count`` ``u0`` round trips on a serial port."""
    times = []
    with serial.Serial(path, 9600, timeout=10) as port:
        for _ in range(count):
            start = time.perf_counter()
            port.write(b"u0\n")
            if len(port.read(4)) != 4:
                raise RuntimeError(f"no reply on {path}")
            times.append((time.perf_counter() - start) * 1000.0)
    return times


def cpu_seconds(pid: int) -> float:
    """CPU seconds (user and system) a process has used, from ``/proc`` (NaN elsewhere)."""
    try:
        with open(f"/proc/{pid}/stat") as stat:
            fields = stat.read().rsplit(")", 1)[1].split()
    except OSError:
        return float("nan")
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")


def _p95(values: list[float]) -> float:
    return statistics.quantiles(values, n=20)[-1]


def main(queries: int = 500) -> list[dict[str, Any]]:
    """Measure and print; the rows."""
    robots = [
        subprocess.Popen(
            [sys.executable, "-c", SERVER], stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True
        )
        for _ in range(2)
    ]
    ports = []
    for robot in robots:
        assert robot.stdout is not None
        ports.append(json.loads(robot.stdout.readline())["serial"])
    robot_port, tapped_robot = ports
    with tempfile.TemporaryDirectory() as folder:
        tap = subprocess.Popen(
            [sys.executable, "-m", "simmer", "tap", tapped_robot, "--config", str(CONFIG),
             "--record", f"{folder}/run"],
            stdout=subprocess.PIPE,
            text=True,
        )  # fmt: skip
        assert tap.stdout is not None
        tap_port = tap.stdout.readline().split()[2]
        before = cpu_seconds(tap.pid)
        direct: list[float] = []
        tapped: list[float] = []
        try:
            for _ in range(5):  # in turns: load falls on both alike
                direct += round_trips(robot_port, queries // 5)
                tapped += round_trips(tap_port, queries // 5)
            cpu = cpu_seconds(tap.pid) - before
        finally:
            tap.send_signal(2)
            tap.wait(30)
            for robot in robots:
                assert robot.stdin is not None
                robot.stdin.close()
                robot.wait(30)
        recorded = json.loads(Path(f"{folder}/run/report.json").read_text())["exchanges"]
    rows = [
        {"path": "direct", "median_ms": statistics.median(direct), "p95_ms": _p95(direct)},
        {"path": "tapped", "median_ms": statistics.median(tapped), "p95_ms": _p95(tapped)},
    ]
    added = rows[1]["median_ms"] - rows[0]["median_ms"]
    print(f"simmer tap: {queries} u0 round trips each way, serial (pseudo-terminal) robot")
    for row in rows:
        print(f"  {row['path']:7s} median {row['median_ms']:.3f} ms   p95 {row['p95_ms']:.3f} ms")
    print(
        f"  added by the tap: {added:.3f} ms median "
        f"({rows[1]['median_ms'] / rows[0]['median_ms']:.2f}x); "
        f"{recorded} exchanges recorded"
    )
    print(
        f"  the tap's own CPU per exchange (forward both ways, decode, record): "
        f"{cpu / queries * 1000:.3f} ms"
    )
    rows.append(
        {"path": "added", "median_ms": added, "recorded": recorded, "cpu_ms": cpu / queries * 1e3}
    )
    return rows


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--queries", type=int, default=500)
    main(parser.parse_args().queries)
