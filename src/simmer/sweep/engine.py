"""Run a sweep's runs on an executor and record each as it finishes.

The engine is any :class:`concurrent.futures.Executor` given picklable :class:`RunSpec`
descriptions: a local process pool by default (``spawn``ed workers, which import the simulator
once and keep their configurations cached), or a Dask cluster's executor. A run's own failures
are recorded by the worker (:func:`~simmer.sweep.runs.execute`); a worker process that dies is
recorded here as ``crashed`` after one retry, and the sweep goes on with a fresh pool.
"""

from __future__ import annotations

import importlib
import multiprocessing
import os
import time
from collections.abc import Callable, Iterator
from concurrent.futures import FIRST_COMPLETED, Executor, Future, ProcessPoolExecutor, wait
from concurrent.futures.process import BrokenProcessPool
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path

from rich.console import Console
from rich.progress import (
    BarColumn,
    MofNCompleteColumn,
    Progress,
    TaskProgressColumn,
    TextColumn,
    TimeElapsedColumn,
    TimeRemainingColumn,
)

from simmer.sweep.results import ResultsFile, flat_outcome, header, row, write_summary
from simmer.sweep.runs import RunResult, RunSpec, execute
from simmer.sweep.spec import SweepSpec, success_condition

Engine = Callable[[], Executor]
"""Makes a fresh executor (called again if a local pool breaks)."""


@dataclass(frozen=True)
class SweepResult:
    """What :func:`run_sweep` did."""

    folder: Path
    runs: int
    """Runs in the sweep."""
    ran: int
    """Runs carried out now (the others were in results.csv already)."""
    successes: int
    """Successes among all the sweep's runs in results.csv."""
    wall_time: float


def local_pool(workers: int | None = None) -> Engine:
    """A pool of ``workers`` processes (default: one per core) started with ``spawn``, so
    no thread or open port of this process is copied into them."""
    count = workers or os.cpu_count() or 1
    context = multiprocessing.get_context("spawn")
    return lambda: ProcessPoolExecutor(max_workers=count, mp_context=context)


def dask_engine(address: str | None = None, workers: int | None = None) -> Engine:
    """The executor of a Dask cluster at ``address``, or of a local cluster of ``workers``
    processes; needs ``pip install "simmer[dask]"``."""
    try:  # an optional extra, imported by name: mypy need not know it
        distributed = importlib.import_module("distributed")
    except ImportError:
        raise RuntimeError(
            'the dask engine needs Dask: pip install "simmer[dask]" (dask[distributed])'
        ) from None

    def make() -> Executor:
        if address is not None:
            client = distributed.Client(address)
        else:
            cluster = distributed.LocalCluster(
                n_workers=workers or os.cpu_count() or 1, threads_per_worker=1
            )
            client = distributed.Client(cluster)
        return client.get_executor()  # type: ignore[no-any-return]

    return make


def run_sweep(
    spec: SweepSpec,
    folder: Path,
    *,
    engine: Engine | None = None,
    workers: int | None = None,
    resume: bool = False,
    console: Console | None = None,
    source: str = "",
) -> SweepResult:
    """Run every run of ``spec`` not yet in ``folder``/results.csv (``resume``), append each
    row as it finishes, then put the table in the sweep's order and write summary.md."""
    started = time.perf_counter()
    runs = spec.runs()
    results = ResultsFile(folder / "results.csv", header(spec), resume=resume)
    todo = [run for run in runs if run.key() not in results.done]
    succeeded = success_condition(spec.success)
    success_column = results.columns.index("success")
    successes = sum(cells[success_column] == "True" for cells in results.done.values())

    with _progress(console, len(runs), len(runs) - len(todo)) as advance:

        def record(run: RunSpec, result: RunResult) -> None:
            nonlocal successes
            ok = result.outcome is not None and succeeded(flat_outcome(result.outcome))
            successes += ok
            results.add(row(run, result, ok))
            advance(successes)

        try:
            _execute_all(
                todo, engine or local_pool(workers), workers or os.cpu_count() or 1, record
            )
        finally:
            complete = all(run.key() in results.done for run in runs)
            results.close([run.key() for run in runs] if complete else None)
    from simmer.sweep.pictures import draw_pictures

    write_summary(folder, spec, source, draw_pictures)
    return SweepResult(folder, len(runs), len(todo), successes, time.perf_counter() - started)


def _execute_all(
    runs: list[RunSpec],
    engine: Engine,
    width: int,
    record: Callable[[RunSpec, RunResult], None],
) -> None:
    """Keep ``2 * width`` runs in flight on the engine's executor, recording each as it
    finishes; a broken pool's runs in flight are retried once on a fresh pool, then recorded
    as ``crashed``."""
    waiting = list(reversed(runs))
    retried: set[str] = set()
    while waiting:
        executor = engine()
        flight: dict[Future[RunResult], RunSpec] = {}
        broken: list[RunSpec] = []
        dead = False
        try:
            while waiting or flight:
                while not dead and waiting and len(flight) < _room(flight, waiting, retried, width):
                    run = waiting.pop()
                    try:
                        flight[executor.submit(execute, run)] = run
                    except BrokenProcessPool:  # never started: it goes to the next pool
                        waiting.append(run)
                        dead = True
                if not flight:
                    break
                done, _ = wait(flight, return_when=FIRST_COMPLETED)
                for future in done:
                    run = flight.pop(future)
                    try:
                        record(run, future.result())
                    except BrokenProcessPool:
                        broken.append(run)
                        dead = True
        finally:
            executor.shutdown(wait=True, cancel_futures=True)
        for run in broken:
            if run.key() in retried:
                detail = "the worker process died during this run (twice)"
                record(run, RunResult(run.key(), "crashed", None, 0.0, None, detail))
            else:
                retried.add(run.key())
                waiting.append(run)


def _room(
    flight: dict[Future[RunResult], RunSpec], waiting: list[RunSpec], retried: set[str], width: int
) -> int:
    """Runs allowed in flight: one at a time while a run that was in flight when a worker died
    is retried (so a run that kills its worker cannot take another with it twice)."""
    suspects = [run for run in (*flight.values(), *waiting[-1:]) if run.key() in retried]
    return 1 if suspects else 2 * width


@contextmanager
def _progress(console: Console | None, total: int, done: int) -> Iterator[Callable[[int], None]]:
    """A progress bar (runs done, rate, ETA, success so far); yields what advances it by one
    run, given the successes so far. Without a console, nothing is shown."""
    if console is None:
        yield lambda _successes: None
        return
    columns = (
        TextColumn("sweep"),
        BarColumn(),
        MofNCompleteColumn(),
        TaskProgressColumn(),
        TextColumn("{task.fields[rate]}"),
        TimeElapsedColumn(),
        TextColumn("ETA"),
        TimeRemainingColumn(),
        TextColumn("{task.fields[success]}"),
    )
    started = time.perf_counter()
    with Progress(*columns, console=console, transient=False) as progress:
        task = progress.add_task("sweep", total=total, completed=done, rate="", success="")
        counted = [done]

        def advance(successes: int) -> None:
            counted[0] += 1
            ran = counted[0] - done
            per_minute = ran / max(time.perf_counter() - started, 1e-9) * 60
            progress.update(
                task,
                advance=1,
                rate=f"{per_minute:.0f} runs/min",
                success=f"success {successes}/{counted[0]} ({successes / counted[0]:.0%})",
            )

        yield advance
