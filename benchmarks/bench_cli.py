"""The command line answers at once: wall time and peak memory of ``simmer --help`` and of each
command's ``--help``, and of importing the light modules (the event types, the client).

Each figure is the median wall time of five fresh processes (the installed ``simmer`` console
script, as a student types it) and the largest peak resident memory among them. Targets (issue
19): 0.3 s and 50 MB for every help page.

Run: ``.venv/bin/python benchmarks/bench_cli.py``.
"""

from __future__ import annotations

import os
import statistics
import subprocess
import sys
import time
from pathlib import Path

TARGET_SECONDS = 0.3
TARGET_MB = 50.0
REPEATS = 5
COMMANDS = ["new", "check", "keys", "run", "convert", "plot", "replay", "render", "sweep",
            "console"]  # fmt: skip
SIMMER = Path(sys.executable).with_name("simmer")


def measure(command: list[str], repeats: int = REPEATS) -> tuple[float, float]:
    """(median wall seconds, largest peak RSS in MB) of running ``command`` ``repeats`` times."""
    walls, peaks = [], []
    for _ in range(repeats):
        start = time.perf_counter()
        process = subprocess.Popen(command, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
        _, status, usage = os.wait4(process.pid, 0)  # this child's own peak, not all children's
        walls.append(time.perf_counter() - start)
        process.returncode = os.waitstatus_to_exitcode(status)
        if process.returncode != 0:
            raise SystemExit(f"{' '.join(command)} failed: {process.stderr.read().decode()}")
        peaks.append(usage.ru_maxrss / 1024)  # kilobytes on Linux
    return statistics.median(walls), max(peaks)


def main() -> dict[str, tuple[float, float]]:
    """Measure, print a table against the targets, return the figures."""
    runs = {"simmer --help": [str(SIMMER), "--help"]}
    runs |= {f"simmer {name} --help": [str(SIMMER), name, "--help"] for name in COMMANDS}
    imports = {
        f"import {module}": [sys.executable, "-c", f"import {module}"]
        for module in ("simmer.world.events", "simmer.client")
    }
    figures = {label: measure(command) for label, command in (runs | imports).items()}
    print("SimMeR command line: median wall time and peak RSS of a fresh process")
    for label, (seconds, mb) in figures.items():
        verdict = ""
        if label in runs:
            ok = seconds <= TARGET_SECONDS and mb <= TARGET_MB
            verdict = "meets" if ok else "MISSES"
        target = f"<= {TARGET_SECONDS} s, {TARGET_MB:.0f} MB" if label in runs else ""
        print(f"  {label:<28} {seconds:6.3f} s {mb:6.1f} MB   {target:<18} {verdict}")
    return figures


if __name__ == "__main__":
    main()
