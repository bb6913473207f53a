"""Batched simulator benchmark (issue 36): robot-steps per second of a batch with four
ultrasonic sensors read every step, at N = 1, 64, 1,024 and 16,384; the ratio to the single
robot's loop; memory per robot; the vector environment's overhead over the raw batch.

Run ``python benchmarks/bench_batch.py`` (or ``python benchmarks/run.py``). Figures are
wall-clock on this machine, each the best of several repeats after a warm-up that compiles
(or loads from cache) the kernels.
"""

from __future__ import annotations

import time
import tracemalloc
from typing import Any

import numpy as np

from simmer import Simulation
from simmer.batch import Batch
from simmer.config import load_config
from simmer.config.overrides import with_overrides

REPEATS = 3
SIZES = (1, 64, 1024, 16384)
TARGETS = {"robot_steps": 500_000.0}
NOISE = {f"sensors.u{k}.error": 0.02 for k in range(4)} | {
    "drives.w0.error.y": 0.02,
    "drives.r0.error.rotation": 0.02,
}


def config() -> Any:
    """The default rover (four ultrasonic sensors read every step) with 2% noise."""
    return with_overrides(load_config(None), NOISE)


CPU: dict[str, float] = {}
"""The CPU seconds of the best repeat of the last :func:`best` (a loaded machine's wall time
says more about the load than about the code)."""


def best(run: Any, repeats: int = REPEATS) -> float:
    """The shortest of ``repeats`` timings of ``run()``, in wall seconds (its CPU seconds in
    ``CPU["last"]``)."""
    times = []
    for _ in range(repeats):
        start, cpu = time.perf_counter(), time.process_time()
        run()
        times.append((time.perf_counter() - start, time.process_time() - cpu))
    wall, CPU["last"] = min(times)
    return wall


def commands(n: int, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    """A random drive command for every robot (the batch refuses those still moving)."""
    drive = rng.integers(0, 2, n)
    amount = np.where(drive == 0, rng.uniform(-6, 10, n), rng.uniform(-90, 90, n))
    return drive, amount


def batch_rate(n: int, steps: int, threads: int = 1) -> tuple[float, float]:
    """Robot-steps per wall and per CPU second of a batch of ``n``: a command every 20 steps,
    sensors every step."""
    batch = Batch(config(), list(range(n)), threads=threads)
    rng = np.random.default_rng(0)
    batch.step(*commands(n, rng), steps=2)  # warm-up and compile

    def run() -> None:
        for _ in range(steps // 20):
            batch.step(*commands(n, rng))
            batch.step(steps=19)

    done = n * (steps // 20) * 20
    return done / best(run), done / CPU["last"]


def single_rate(steps: int) -> tuple[float, float]:
    """Steps per second of one Simulation doing the same (``simulate_list`` reads the four
    sensors each step)."""
    sim = Simulation(config(), seed=0)
    rng = np.random.default_rng(0)
    sim.step(2)

    def run() -> None:
        for _ in range(steps // 20):
            drive, amount = commands(1, rng)
            sim.command(f"{('w0', 'r0')[int(drive[0])]}-{float(amount[0])!r}")
            sim.step(20)

    done = (steps // 20) * 20
    return done / best(run), done / CPU["last"]


def memory_per_robot(n: int = 4096) -> float:
    """Bytes a batch holds per robot (arrays, noise blocks and streams)."""
    cfg = config()
    Batch(cfg, [0])
    tracemalloc.start()
    batch = Batch(cfg, list(range(n)))
    batch.step()
    size, _ = tracemalloc.get_traced_memory()
    tracemalloc.stop()
    return size / n


def vector_overhead(n: int = 1024, actions: int = 20) -> tuple[float, float]:
    """Seconds per action of the vector environment and of the same batch calls by hand."""
    from simmer.gym import MazeVectorEnv

    envs = MazeVectorEnv(n, overrides=NOISE, max_steps=10_000)
    envs.reset(seed=0)
    rng = np.random.default_rng(1)
    envs.step(rng.integers(0, 2, n))

    def env_run() -> None:
        for _ in range(actions):
            envs.step(np.zeros(n, dtype=np.int64))

    batch = Batch(config(), list(range(n)))
    frames = envs.task.forward_frames
    drive = np.zeros(n, dtype=np.int64)
    amount = np.full(n, envs.task.forward)

    def raw_run() -> None:
        for _ in range(actions):
            batch.step(drive, amount, frames)

    return best(env_run) / actions, best(raw_run) / actions


def main() -> None:
    """Print the figures and their ratios (per wall second, and per CPU second)."""
    print("batch: robot-steps/s, four ultrasonic sensors read every step (2% noise)")
    single, single_cpu = single_rate(3000)
    print(f"  single Simulation loop     {single:>11,.0f} /s wall  {single_cpu:>11,.0f} /s CPU")
    top = 0.0
    for n in SIZES:
        steps = max(200, min(20_000, 2_000_000 // n))
        wall, cpu = batch_rate(n, steps)
        top = max(top, wall)
        print(
            f"  batch N = {n:>6,}            {wall:>11,.0f} /s wall  {cpu:>11,.0f} /s CPU"
            f"  ({wall / single:,.1f}x the single loop, {cpu / single_cpu:,.1f}x per CPU s)"
        )
    wall, cpu = batch_rate(16384, 200, threads=2)
    top = max(top, wall)
    print(f"  batch N = 16,384, 2 threads {wall:>10,.0f} /s wall  {cpu:>11,.0f} /s CPU")
    mark = "ok" if top >= TARGETS["robot_steps"] else "below target (see the CPU figures)"
    print(f"  best {top:,.0f} robot-steps/s wall (target {TARGETS['robot_steps']:,.0f}): {mark}")
    print(f"  memory per robot           {memory_per_robot():>11,.0f} bytes")
    env_s, raw_s = vector_overhead()
    print(
        f"  vector env, N = 1,024: {env_s * 1e3:.2f} ms per action, raw batch {raw_s * 1e3:.2f} ms"
        f" ({env_s / raw_s - 1:+.0%} overhead)"
    )


if __name__ == "__main__":
    main()
