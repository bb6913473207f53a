"""Link-model benchmark: what the ``[link]`` model (docs/link.md) costs.

Run ``python benchmarks/bench_link_model.py`` (or ``python benchmarks/run.py``). Figures are
medians of several runs on this machine:

* the model alone: one message through :meth:`LinkModel.carry` (``u0\\n`` there, its 7-byte
  frame back), with no loss and with the HC-05's loss and corruption; and 100,000 bytes in
  messages of 100 with 1% lost and 1% corrupted;
* a served run: a ``simmer.client`` program reading ``u0`` 300 times under ``--program``,
  wall milliseconds per message with the model off and with ``hc05-9600`` (its losses and
  dropouts set to 0, so every read succeeds; a run of one read subtracted), and the
  simulated seconds a read then takes on the program's clock.
"""

from __future__ import annotations

import contextlib
import dataclasses
import os
import statistics
import sys
import tempfile
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

from simmer import Simulation
from simmer.config.link import PRESETS
from simmer.options import RunOptions
from simmer.serve import serve
from simmer.sweep import build_config
from simmer.transport.link import TO_PROGRAM, TO_ROBOT, LinkModel

ROOT = Path(__file__).resolve().parent.parent
LAB1 = ROOT / "examples" / "lab1_rover.toml"
MESSAGES = 300
REPEATS = 5
PROGRAM = """
import time
from simmer.client import connect
with connect() as robot:
    start = time.monotonic()
    for _ in range({n}):
        robot.read('u0')
    seconds = (time.monotonic() - start) / {n}
open({out!r}, "w").write(repr(seconds))
"""


def model(**changes: float) -> LinkModel:
    """The hc05-9600 model with ``changes``, its streams from seed 1."""
    import numpy as np

    params = dataclasses.replace(PRESETS["hc05-9600"], **changes)
    return LinkModel(params, lambda name: np.random.default_rng(abs(hash(name)) % 2**32))


def per_message(link: LinkModel, count: int = 20_000) -> float:
    """Microseconds for one exchange (command and reply) through ``link``."""
    frame = b"\x04\x01\x00\x00\x00\x1eB"
    started = time.perf_counter()
    for i in range(count):
        now = i * 0.05
        link.carry(b"u0\n", now, TO_ROBOT)
        link.carry(frame, now, TO_PROGRAM)
    return (time.perf_counter() - started) / count * 1e6


def hundred_thousand_bytes() -> float:
    """Milliseconds for 100,000 bytes in messages of 100, 1% lost and 1% corrupted."""
    link = model(loss=0.01, corruption=0.01, dropout_every=0)
    data = bytes(range(100))
    started = time.perf_counter()
    for i in range(1000):
        link.carry(data, i * 0.2, TO_ROBOT)
    return (time.perf_counter() - started) * 1e3


@contextlib.contextmanager
def quiet() -> Iterator[None]:
    """Send what the programs print (this process's standard output) to nowhere."""
    sys.stdout.flush()
    saved = os.dup(1)
    with tempfile.TemporaryFile() as sink:
        os.dup2(sink.fileno(), 1)
        try:
            yield
        finally:
            os.dup2(saved, 1)
            os.close(saved)


def served(link: dict[str, Any] | None, program: Path) -> float:
    """Wall seconds of one ``--program`` run of ``program`` with ``[link]`` = ``link``."""
    overrides = () if link is None else (("link", link),)
    sim = Simulation(build_config(str(LAB1), overrides), seed=1)
    options = RunOptions.free_ports(
        speed=None, program=f"{sys.executable} {program}", timeout=120, clock="lockstep"
    )
    started = time.perf_counter()
    with quiet():
        done = serve(sim, options, echo=lambda _line: None)
    seconds = time.perf_counter() - started
    if done.exit_status != 0:
        raise SystemExit(f"the benchmark's program failed ({done.exit_status})")
    return seconds


def main() -> None:
    """Print the figures (see the module doc)."""
    print("link model (benchmarks/bench_link_model.py)")
    clean = statistics.median(per_message(model(loss=0, corruption=0)) for _ in range(REPEATS))
    lossy = statistics.median(per_message(model()) for _ in range(REPEATS))
    bulk = statistics.median(hundred_thousand_bytes() for _ in range(REPEATS))
    print(f"  LinkModel, one exchange (u0 and its frame), no loss: {clean:.1f} us")
    print(f"  LinkModel, one exchange, hc05-9600 loss and corruption: {lossy:.1f} us")
    print(f"  LinkModel, 100,000 bytes, 1% lost and 1% corrupted: {bulk:.1f} ms")
    with tempfile.TemporaryDirectory() as folder:
        out = Path(folder) / "simulated.txt"
        many = Path(folder) / "many.py"
        many.write_text(PROGRAM.format(n=MESSAGES, out=str(out)), encoding="utf-8")
        none = Path(folder) / "none.py"
        none.write_text(PROGRAM.format(n=1, out=str(Path(folder) / "one.txt")), encoding="utf-8")
        hc05 = {"preset": "hc05-9600", "loss": 0, "corruption": 0, "dropout_every": 0}
        figures = {}
        for name, link in (("off", None), ("hc05-9600", hc05)):
            full = statistics.median(served(link, many) for _ in range(REPEATS))
            base = statistics.median(served(link, none) for _ in range(REPEATS))
            figures[name] = (full - base) / (MESSAGES - 1) * 1e3
            simulated = float(out.read_text(encoding="utf-8"))
        off, on = figures["off"], figures["hc05-9600"]
    print(f"  served read of u0 under --program, model off: {off:.3f} ms wall a message")
    print(f"  served read of u0 under --program, hc05-9600: {on:.3f} ms wall a message")
    print(f"  ratio (model on / off): {on / off:.2f}")
    expected = 2 * 0.012 + 2 * 0.004 + 10 * 10 / 9600
    print(
        f"  simulated time a read takes with hc05-9600: {simulated * 1e3:.2f} ms on average "
        f"(expected {expected * 1e3:.2f}: 2 x 12 ms latency, 2 x 4 ms mean jitter, 10 bytes "
        "at 9600 baud)"
    )


if __name__ == "__main__":
    main()
