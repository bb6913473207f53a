"""Run a sweep's runs on an executor, record each as it finishes, then film the first failures.

The engine is any :class:`concurrent.futures.Executor` given picklable :class:`RunSpec`
descriptions: a local process pool by default (on Linux, workers forked from a server that has
the simulator loaded; elsewhere ``spawn``ed ones; each keeps its configurations cached and a
simulation warm), or a Dask cluster's executor (:func:`dask_engine`: a scheduler's address,
or a local cluster of worker processes). Ray is
not offered: it is a heavy dependency for what Dask already does here, and would sit behind the
same interface as one more ``concurrent.futures`` executor. A run's own failures are recorded by
the worker (:func:`~simmer.sweep.runs.execute`); a local worker process that dies is recorded
here as ``crashed`` after one retry, and the sweep goes on with a fresh pool (Dask restarts its
workers itself, and a run it gives up on is recorded as ``crashed`` too).

When every run is in the table, the first ``videos`` failures in the sweep's order (the same
ones whatever the engine and however runs finished) are run again with a video, on the same
executor: a run is repeatable, and a filmed run that went otherwise is said so in the summary.
"""

from __future__ import annotations

import _thread
import ctypes
import importlib
import multiprocessing
import os
import signal
import sys
import threading
import time
from collections.abc import Callable, Iterator
from concurrent.futures import FIRST_COMPLETED, Executor, Future, ProcessPoolExecutor, wait
from concurrent.futures.process import BrokenProcessPool
from contextlib import contextmanager, suppress
from dataclasses import dataclass
from pathlib import Path
from types import FrameType
from typing import Any, ParamSpec, TypeVar

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

from simmer.ending import RunEnd
from simmer.errors import SweepError, SweepStopped
from simmer.proctree import adopt_orphans, descendants, still_running, stop_strays
from simmer.record.safefile import write_bytes
from simmer.sweep.results import (
    ResultsFile,
    header,
    keep_files,
    outcome_cells,
    read_rows,
    row,
    write_summary,
)
from simmer.sweep.runs import RunResult, RunSpec, execute, film
from simmer.sweep.spec import SweepSpec
from simmer.sweep.success import OUTCOME_FIELDS

Engine = Callable[[], Executor]
"""Makes a fresh executor (called again if a local pool breaks). An executor with a ``width``
attribute (runs it carries out at once) gets twice that many runs at a time."""
Work = Callable[[RunSpec], RunResult]
P = ParamSpec("P")
T = TypeVar("T")


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
    filmed: int = 0
    """Failures filmed now."""


PARENT_POLL = 0.5
"""Wall seconds between a worker's checks that the sweep that started it is still there."""
PARENT_GRACE = 10.0
"""Wall seconds a worker whose sweep is gone gives its run's program to stop (as Ctrl-C stops
it) before it stops what is left and exits."""
STOP_SIGNALS = ("SIGINT", "SIGTERM", "SIGHUP")
"""Signals that stop a sweep cleanly (Ctrl-C, ``kill``, closing the terminal), where they exist."""

DASK_WORKER_THREADS = 1
"""Threads a Dask worker may run tasks on: a worker process runs one run at a time."""

_stopping: ctypes.c_bool | None = None
"""In a local pool's worker: the pool's flag, set when the sweep stops (:func:`_watch_sweep`)."""


def local_pool(workers: int | None = None) -> Engine:
    """A pool of ``workers`` processes (default: one per core), none a copy of this process
    (no thread or open port of it is copied into them): on Linux each is forked from a
    server that has imported the simulator and loaded its compiled functions once
    (:mod:`simmer.sweep.preload`), so it starts in milliseconds instead of a second of
    CPU; elsewhere each is ``spawn``ed (Windows has nothing else; on macOS a fork can break
    the system's frameworks). Each worker exits by itself if this process goes away
    (:func:`_watch_sweep`)."""
    count = workers or os.cpu_count() or 1
    if sys.platform.startswith("linux"):
        context: multiprocessing.context.BaseContext = multiprocessing.get_context("forkserver")
        context.set_forkserver_preload(["simmer.sweep.preload"])
    else:
        context = multiprocessing.get_context("spawn")
    _start_helpers(fork_server=context.get_start_method() == "forkserver")
    stopping = context.RawValue(ctypes.c_bool, False)  # shared memory: set without a lock

    def make() -> _LocalPool:
        started = context.SimpleQueue()  # each worker's pid, put there as it starts
        return _LocalPool(
            stopping,
            started,
            max_workers=count,
            mp_context=context,
            initializer=_watch_sweep,
            initargs=(os.getpid(), stopping, started),
        )

    return make


def _start_helpers(*, fork_server: bool) -> None:
    """Start multiprocessing's resource tracker (and, with ``fork_server``, the fork server a
    local pool's workers come from) ignoring SIGHUP, which they keep. They are in the sweep's
    process group, which a closed terminal signals, and neither stops on SIGHUP by itself:
    killed by it, the tracker was started again as the sweep stopped, with a warning ("Some
    resources might leak") and a traceback for each semaphore it then failed to find. Workers
    forked from the server ignore it too until a run takes it (:func:`simmer.serve.serve`);
    the sweep stops them itself. Off the main thread, where a handler cannot be set, they
    start when first needed."""
    hangup = getattr(signal, "SIGHUP", None)
    if hangup is None or threading.current_thread() is not threading.main_thread():
        return  # Windows: no SIGHUP, no tracker, no server
    from multiprocessing import forkserver, resource_tracker

    previous = signal.signal(hangup, signal.SIG_IGN)
    try:
        resource_tracker.ensure_running()
        if fork_server:
            forkserver.ensure_running()
    finally:
        signal.signal(hangup, previous)


class _LocalPool(ProcessPoolExecutor):
    """A local pool whose workers start no run once ``stopping`` is set (:meth:`Pool.stop`):
    a run queued before a stop would otherwise start after it, and run to its wall limit.
    Its workers' pids come from the workers themselves (``started``), not from the
    executor's private records."""

    def __init__(self, stopping: ctypes.c_bool, started: Any, **options: Any) -> None:
        super().__init__(**options)
        self.stopping = stopping
        self._started = started
        self._pids: set[int] = set()

    def worker_pids(self) -> set[int]:
        """The pids of the workers started so far (each put its own on ``started``)."""
        while not self._started.empty():
            self._pids.add(self._started.get())
        return set(self._pids)


def _unless_stopping(work: Work, run: RunSpec) -> RunResult:
    """In a worker: ``work(run)``, unless its sweep is stopping; then the run does not start
    (status ``stopped``, never recorded: the sweep records no row once it is stopped)."""
    if _stopping is not None and _stopping.value:
        return RunResult(run.key(), RunEnd.STOPPED, None, 0.0, detail="the sweep was stopped first")
    return work(run)


def _watch_sweep(sweep: int, stopping: ctypes.c_bool, started: Any) -> None:
    """In a worker: when the ``sweep`` that started it is gone (``kill -9``, a crash), stop
    the run in progress as Ctrl-C would (its program's whole tree with it) and exit; a worker
    is otherwise left waiting for work forever (the sweep is watched by its pid, not as the
    worker's parent: a forked worker's parent is the fork server, which stays while any worker
    does). The worker also becomes the subreaper of the programs it starts
    (:mod:`simmer.proctree`), keeps its pool's ``stopping`` flag (:func:`_unless_stopping`)
    and puts its pid on ``started`` (for :meth:`_LocalPool.worker_pids`)."""
    global _stopping  # noqa: PLW0603 (the worker's one flag, set by its initializer)
    _stopping = stopping
    started.put(os.getpid())
    running = still_running(sweep)
    adopt_orphans()
    gone = threading.Event()

    def watch() -> None:
        while not gone.wait(PARENT_POLL):
            if not running():
                gone.set()
        _thread.interrupt_main()  # a run in progress stops, as with Ctrl-C
        deadline = time.monotonic() + PARENT_GRACE
        while descendants() and time.monotonic() < deadline:  # its program is being stopped
            threading.Event().wait(PARENT_POLL / 5)
        stop_strays(set())
        os._exit(1)

    threading.Thread(target=watch, name="simmer-parent-watch", daemon=True).start()


@contextmanager
def _stopped_by_signals(pool: Pool) -> Iterator[None]:
    """Within ``with``: :data:`STOP_SIGNALS` stop the sweep as Ctrl-C does: the runs stop
    (:meth:`Pool.stop`), and :class:`SweepStopped` is raised here, where the pool is then
    shut down. Only in the main thread. Ctrl-C or a closed terminal signals the workers too:
    the SIGINT sent here then reaches a run that is stopping already, which only notes it
    (:func:`simmer.serve.serve`)."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    stopping: list[int] = []

    def handle(signum: int, _frame: FrameType | None) -> None:
        pool.stop()
        if not stopping:  # once: a second signal must not interrupt the shutdown
            stopping.append(signum)
            raise SweepStopped(signum)

    previous = {}
    for name in STOP_SIGNALS:
        if (number := getattr(signal, name, None)) is not None:
            previous[number] = signal.signal(number, handle)
    try:
        yield
    finally:
        for number, handler in previous.items():
            signal.signal(number, handler)


class DaskExecutor(Executor):
    """A Dask client's executor that closes the client, and the local cluster it runs on if
    it started one, when it shuts down. ``width``: the cluster's threads. A cluster whose
    workers run more than :data:`DASK_WORKER_THREADS` task at once is refused
    (:class:`~simmer.errors.SweepError`, and the client closed): the runs of one worker
    process would share its simulations, its policies and its signal handlers."""

    def __init__(self, client: Any, cluster: Any = None) -> None:
        self.client = client
        self.cluster = cluster
        threads: dict[str, int] = client.nthreads()
        crowded = sorted(address for address, count in threads.items() if count > 1)
        if crowded:
            client.close()
            if cluster is not None:
                cluster.close()
            raise SweepError(
                f"the Dask worker {crowded[0]} runs {threads[crowded[0]]} threads; a sweep "
                f"needs workers with {DASK_WORKER_THREADS} thread each "
                f"(DASK_WORKER_THREADS): start them with --nthreads 1"
            )
        self._inner: Executor = client.get_executor(pure=False)  # a retried run runs again
        self.width = max(1, sum(threads.values()))

    def submit(self, fn: Callable[P, T], /, *args: P.args, **kwargs: P.kwargs) -> Future[T]:
        """Run ``fn(*args, **kwargs)`` on the cluster."""
        return self._inner.submit(fn, *args, **kwargs)

    def shutdown(self, wait: bool = True, *, cancel_futures: bool = False) -> None:
        """Wait for (or cancel) what was submitted, then close the client and our cluster."""
        self._inner.shutdown(wait=wait and not cancel_futures)
        self.client.close()
        if self.cluster is not None:
            self.cluster.close()


LOOPBACK = "127.0.0.1"
"""Where a local Dask cluster listens (scheduler, workers, dashboard), as every other socket
of SimMeR does: a cluster reachable from the network would run whatever task it is sent."""


def dask_engine(address: str | None = None, workers: int | None = None) -> Engine:
    """The executor of a Dask cluster at ``address``, or of a local cluster of ``workers``
    processes (default: one per core) with one thread each, closed with the sweep; needs
    ``pip install "simmer[dask]"``."""
    try:  # an optional extra, imported by name: mypy need not know it
        distributed = importlib.import_module("distributed")
    except ImportError:
        raise RuntimeError(
            'the dask engine needs Dask: pip install "simmer[dask]" (dask[distributed])'
        ) from None
    count = workers or os.cpu_count() or 1

    def make() -> Executor:
        if address is not None:
            return DaskExecutor(distributed.Client(address))
        _start_helpers(fork_server=False)  # the cluster's processes start through multiprocessing
        cluster = distributed.LocalCluster(
            n_workers=count,
            threads_per_worker=1,
            processes=True,
            host=LOOPBACK,  # the scheduler and the workers: this machine only
            dashboard_address=f"{LOOPBACK}:0",  # ":0" bound every interface; a free port
        )
        try:
            client = distributed.Client(cluster)
            client.wait_for_workers(count)
        except BaseException:
            cluster.close()
            raise
        return DaskExecutor(client, cluster)

    return make


class Pool:
    """The engine's executor: made when first needed, made again after a local pool breaks,
    shut down at the end."""

    def __init__(self, engine: Engine, width: int) -> None:
        self.engine = engine
        self.default_width = width
        self._current: Executor | None = None

    def executor(self) -> Executor:
        """The current executor (a new one if there is none)."""
        if self._current is None:
            self._current = self.engine()
        return self._current

    @property
    def width(self) -> int:
        """Runs the executor carries out at once."""
        width = getattr(self._current, "width", None)
        return width if isinstance(width, int) else self.default_width

    def stop(self) -> None:
        """Stop the runs of a local pool: its workers start no more (its ``stopping`` flag)
        and each is sent SIGINT, which stops the run it has and its program's tree. The flag
        is set first, so a run begins before the SIGINT or not at all."""
        current = self._current
        if not isinstance(current, _LocalPool):
            return  # a Dask cluster's runs end as the pool is shut down
        current.stopping.value = True
        for pid in current.worker_pids():
            with suppress(OSError):
                os.kill(pid, signal.SIGINT)

    def close(self, *, cancel: bool = False) -> None:
        """Shut the executor down (waiting for its runs unless ``cancel``)."""
        if self._current is not None:
            current, self._current = self._current, None
            current.shutdown(wait=True, cancel_futures=cancel)


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
    """Check every setting (:meth:`SweepSpec.check_settings`), run every run of ``spec`` not
    yet in ``folder``/results.csv (``resume``), append each row (and write each kept run's
    folder) as it finishes, put the table in the sweep's order, film the first failures, and
    write summary.md."""
    started = time.perf_counter()
    spec.check_settings()
    runs = spec.runs()
    table = Table(folder, header(spec), spec.folder_names(runs), spec.project)
    ran, successes, (filmed, remarks) = run_table(
        runs,
        table,
        lambda pool: _film_failures(spec, runs, folder, pool, console),
        engine=engine,
        workers=workers,
        resume=resume,
        progress=(console, "sweep", True),
    )
    from simmer.sweep.pictures import draw_pictures

    write_summary(folder, spec, source, draw_pictures, remarks)
    elapsed = time.perf_counter() - started
    return SweepResult(folder, len(runs), ran, successes, elapsed, filmed)


@dataclass(frozen=True)
class Table:
    """Where a sweep's or a grading's runs go: ``folder``/results.csv with ``columns``, each
    kept run's files under its name in ``names`` (by run key); ``project``: the rows carry
    the project's fields; ``prepare``: what is done to a result before its row is written."""

    folder: Path
    columns: list[str]
    names: dict[str, str]
    project: bool
    prepare: Callable[[RunResult], RunResult] = lambda result: result


def run_table(
    runs: list[RunSpec],
    table: Table,
    then: Callable[[Pool], T],
    *,
    engine: Engine | None,
    workers: int | None,
    resume: bool,
    progress: tuple[Console | None, str, bool],
) -> tuple[int, int, T]:
    """Run every run not yet in the table (``resume``) on the engine, appending each row and
    keeping its files as it finishes, with a progress bar (console, label, whether it shows
    the successes); close results.csv in the runs' order once every run is in it; then
    ``then(pool)`` on the same pool. Signals stop it all cleanly (:func:`_stopped_by_signals`).
    Returns the runs carried out now, the successes in the whole table, and what ``then`` gave."""
    console, label, show_successes = progress
    pool = Pool(engine or local_pool(workers), workers or os.cpu_count() or 1)
    try:
        pool.executor()  # a refused cluster (DASK_WORKER_THREADS) leaves no results.csv
        results = ResultsFile(table.folder / "results.csv", table.columns, resume=resume)
    except BaseException:
        pool.close(cancel=True)
        raise
    todo = [run for run in runs if run.key() not in results.done]
    success_column = results.columns.index("success")
    successes = sum(cells[success_column] == "True" for cells in results.done.values())
    with _stopped_by_signals(pool):
        try:
            with _progress(console, label, len(runs), len(runs) - len(todo)) as advance:

                def record(run: RunSpec, result: RunResult) -> None:
                    nonlocal successes
                    successes += result.success
                    result = table.prepare(result)
                    name = table.names[run.key()]
                    kept = keep_files(table.folder, name, result.files) if result.files else ""
                    results.add(row(run, result, kept, table.project))
                    advance(successes if show_successes else None)

                try:
                    execute_all(todo, pool, execute, record)
                finally:
                    complete = all(run.key() in results.done for run in runs)
                    results.close([run.key() for run in runs] if complete else None)
            after = then(pool)
        except BaseException:
            pool.close(cancel=True)
            raise
        pool.close()
    return len(todo), successes, after


def to_film(
    runs: list[RunSpec], by_key: dict[str, dict[str, str]], folder: Path, count: int
) -> list[RunSpec]:
    """The first ``count`` failures among ``runs`` (rows of results.csv ``by_key``) that had a
    simulation and kept a folder, less those filmed already (a video in the folder)."""
    failures = [
        run
        for run in runs
        if (r := by_key.get(run.key())) is not None
        and r["failure"]
        and r["folder"]
        and r["status"] not in (RunEnd.CRASHED, RunEnd.INVALID)  # no simulation to film
    ]
    return [
        run
        for run in failures[:count]
        if not (folder / by_key[run.key()]["folder"] / "video.mp4").exists()
    ]


def _film_failures(
    spec: SweepSpec, runs: list[RunSpec], folder: Path, pool: Pool, console: Console | None
) -> tuple[int, list[str]]:
    """Film the first ``spec.videos`` failures in the sweep's order that had a simulation and
    have no video yet, into their run folders; how many, and remarks for the summary."""
    by_key = {r["run"]: r for r in read_rows(folder / "results.csv")}
    todo = to_film(runs, by_key, folder, spec.videos)
    remarks: list[str] = []
    if not todo:
        return 0, remarks
    with _progress(console, "videos", len(todo), 0) as advance:

        def record(run: RunSpec, result: RunResult) -> None:
            cells = by_key[run.key()]
            if "video.mp4" in result.files:
                write_bytes(folder / cells["folder"] / "video.mp4", result.files["video.mp4"])
            else:
                remarks.append(f"No video of `{cells['folder']}`: its filming {result.status}.")
            if result.outcome is not None and outcome_cells(result) != [
                cells[name] for name in OUTCOME_FIELDS
            ]:
                remarks.append(
                    f"The filmed run of `{cells['folder']}` went otherwise than in the sweep "
                    "(is the controller repeatable?)."
                )
            advance(None)

        execute_all(todo, pool, film, record)
    return len(todo), remarks


def execute_all(
    runs: list[RunSpec], pool: Pool, work: Work, record: Callable[[RunSpec, RunResult], None]
) -> None:
    """Keep twice the pool's width of runs in flight, ``work`` doing each, recording each as
    it finishes; a broken local pool's runs in flight are retried once on a fresh pool, then
    recorded as ``crashed``, as is a run the engine gave up on (Dask: its worker kept dying)."""
    waiting = list(reversed(runs))
    retried: set[str] = set()
    while waiting:
        executor = pool.executor()
        width = pool.width
        flight: dict[Future[RunResult], RunSpec] = {}
        broken: list[RunSpec] = []
        dead = False
        while waiting or flight:
            while not dead and waiting and len(flight) < _room(flight, waiting, retried, width):
                run = waiting.pop()
                try:
                    flight[executor.submit(_unless_stopping, work, run)] = run
                except BrokenProcessPool:  # never started: it goes to the next pool
                    waiting.append(run)
                    dead = True
            if not flight:
                break
            done, _ = wait(flight, return_when=FIRST_COMPLETED)
            for future in done:
                run = flight.pop(future)
                try:
                    result = future.result()
                except BrokenProcessPool:
                    broken.append(run)
                    dead = True
                    continue
                except Exception as exc:
                    detail = f"the engine lost this run: {type(exc).__name__}: {exc}"
                    result = RunResult(run.key(), RunEnd.CRASHED, None, 0.0, None, detail)
                record(run, result)
        if dead:
            pool.close(cancel=True)
        for run in broken:
            if run.key() in retried:
                detail = "the worker process died during this run (twice)"
                record(run, RunResult(run.key(), RunEnd.CRASHED, None, 0.0, None, detail))
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
def _progress(
    console: Console | None, label: str, total: int, done: int
) -> Iterator[Callable[[int | None], None]]:
    """A progress bar (runs done, rate, ETA, and the success rate so far if given); yields
    what advances it by one run, given the successes so far or None. Without a console,
    nothing is shown."""
    if console is None:
        yield lambda _successes: None
        return
    columns = (
        TextColumn(label),
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
        task = progress.add_task(label, total=total, completed=done, rate="", success="")
        counted = [done]

        def advance(successes: int | None) -> None:
            counted[0] += 1
            ran = counted[0] - done
            per_minute = ran / max(time.perf_counter() - started, 1e-9) * 60
            share = (
                f"success {successes}/{counted[0]} ({successes / counted[0]:.0%})"
                if successes is not None
                else ""
            )
            progress.update(task, advance=1, rate=f"{per_minute:.0f} runs/min", success=share)

        yield advance
