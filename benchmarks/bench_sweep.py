"""Sweep benchmark: runs per second per worker, fixed cost per run, memory per worker, and the
speed-up from one worker to two.

Run ``python benchmarks/bench_sweep.py`` (or ``python benchmarks/run.py`` for every benchmark).
The runs are the lab's dead-reckoning sequence on the Lab 1 rover: as a program
(``examples/dead_reckoning.py`` under the lockstep clock, one process and its own ports per run)
and as an in-process policy (``dead_reckoning:drive_sequence``, given a client). Figures are
wall-clock on this machine: "per worker" figures run in this process, one run after another,
after a warm-up run; the speed-up runs whole sweeps through the process pool.
"""

from __future__ import annotations

import sys
import tempfile
import time
from concurrent.futures import ProcessPoolExecutor
from multiprocessing import get_context
from pathlib import Path
from typing import Any

from simmer.sweep import run_sweep
from simmer.sweep.runs import RunSpec, execute
from simmer.sweep.spec import sweep_from_dict

ROOT = Path(__file__).resolve().parent.parent
EXAMPLES = ROOT / "examples"
LAB1 = EXAMPLES / "lab1_rover.toml"
PROGRAM = f'"{sys.executable}" -u dead_reckoning.py'
POLICY = "dead_reckoning:drive_sequence"
TARGETS = {"program_runs_per_s": 3.0, "policy_runs_per_s": 50.0}
TRIVIAL = """
import simmer.client  # what a control program imports, then nothing


def nothing(robot):
    '''A policy that sends nothing.'''
"""


def spec_data(kind: str, controller: str, seeds: int) -> dict[str, Any]:
    """A sweep of ``seeds`` runs of one controller on the Lab 1 rover with drive error, as
    Part 2 of the lab has it."""
    return {
        "config": str(LAB1),
        kind: controller,
        "seeds": seeds,
        "seconds": 120,
        "wall_seconds": 60,
        "keep": "nothing",  # what runs cost, not the failures' folders and frames
        # Part 2 of the lab: simulate_list commented out (Part 1's rays cost 4 reads a step)
        "grid": {"drives.w0.error.y": [0.02], "simulate_list": [[]]},
    }


def runs_of(kind: str, controller: str, seeds: int, folder: Path = EXAMPLES) -> list[RunSpec]:
    """The runs of :func:`spec_data`'s sweep, with ``folder`` as the working directory."""
    return sweep_from_dict(spec_data(kind, controller, seeds), folder).runs()


def runs_per_second(runs: list[RunSpec]) -> float:
    """Runs per second carried out one after another in this process, after one warm-up run
    (the configuration read, the kernels compiled); every run must end ``ok``."""
    execute(runs[0])
    started = time.perf_counter()
    for run in runs[1:]:
        result = execute(run)
        if result.status != "ok":
            raise SystemExit(f"a benchmark run ended {result.status}: {result.detail}")
    return (len(runs) - 1) / (time.perf_counter() - started)


def fixed_cost_ms(folder: Path) -> tuple[float, float]:
    """Milliseconds per run of controllers that do nothing: (a program that imports
    ``simmer.client`` and exits, a policy that returns at once)."""
    (folder / "trivial.py").write_text(TRIVIAL, encoding="utf-8")
    program = runs_of("program", f'"{sys.executable}" trivial.py', 11, folder)
    policy = runs_of("policy", "trivial:nothing", 101, folder)
    return 1000 / runs_per_second(program), 1000 / runs_per_second(policy)


def peak_rss_mb() -> float:
    """This process's peak resident set in MB (VmHWM: starts afresh in a spawned process)."""
    for line in Path("/proc/self/status").read_text(encoding="ascii").splitlines():
        if line.startswith("VmHWM:"):
            return int(line.split()[1]) / 1024
    return float("nan")


def worker_memory_mb(runs: list[RunSpec]) -> float:
    """Peak RSS in MB of a spawned pool worker after it has carried out ``runs``."""
    with ProcessPoolExecutor(1, mp_context=get_context("spawn")) as pool:
        for result in pool.map(execute, runs):
            if result.status != "ok":
                raise SystemExit(f"a benchmark run ended {result.status}: {result.detail}")
        return pool.submit(peak_rss_mb).result()


def sweep_runs_per_second(kind: str, controller: str, seeds: int, workers: int) -> float:
    """Runs per second of a whole sweep through the process pool (start-up included)."""
    spec = sweep_from_dict(spec_data(kind, controller, seeds), EXAMPLES)
    with tempfile.TemporaryDirectory() as folder:
        done = run_sweep(spec, Path(folder) / "out", workers=workers)
    return done.runs / done.wall_time


def main() -> dict[str, float]:
    """Run the sweep benchmark and print its figures against targets."""
    figures = {  # what the runs print goes to a pipe of each run's own (execute)
        "program_runs_per_s": runs_per_second(runs_of("program", PROGRAM, 13)),
        "policy_runs_per_s": runs_per_second(runs_of("policy", POLICY, 101)),
    }
    with tempfile.TemporaryDirectory() as folder:
        figures["program_fixed_ms"], figures["policy_fixed_ms"] = fixed_cost_ms(Path(folder))
    figures["worker_mb"] = worker_memory_mb(runs_of("program", PROGRAM, 4))
    for workers in (1, 2):
        figures[f"sweep_{workers}"] = sweep_runs_per_second("program", PROGRAM, 24, workers)
    figures["speedup"] = figures["sweep_2"] / figures["sweep_1"]
    per_core = figures["sweep_2"] / 2
    figures["estimate_64_min"] = 10_000 / (per_core * 64) / 60

    rows = [
        ("program runs/s per worker (dead reckoning, lockstep)", "program_runs_per_s", ">= 3"),
        ("policy runs/s per worker (the same moves, in-process)", "policy_runs_per_s", ">= 50"),
        ("fixed cost per run, ms: a program that only imports", "program_fixed_ms", ""),
        ("fixed cost per run, ms: a policy that returns at once", "policy_fixed_ms", ""),
        ("peak RSS of a pool worker after 4 program runs, MB", "worker_mb", ""),
        ("sweep of 24 program runs, 1 worker: runs/s (pool start-up included)", "sweep_1", ""),
        ("the same, 2 workers: runs/s", "sweep_2", ""),
        ("  speed-up from 1 to 2 workers", "speedup", ""),
        ("10,000 program runs on 64 such cores, minutes (estimate)", "estimate_64_min", ""),
    ]
    print("SimMeR sweep benchmark")
    for label, key, target in rows:
        value = figures[key]
        verdict = ""
        if key in TARGETS:
            verdict = "ok" if value >= TARGETS[key] else "MISSED"
        print(f"  {label:<72} {value:10.2f}  {target:>6} {verdict}")
    return figures


if __name__ == "__main__":
    main()
