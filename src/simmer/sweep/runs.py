"""One run of a sweep: a small picklable description (:class:`RunSpec`) and the worker that
carries it out (:func:`execute`), recording whatever happens as a :class:`RunResult`.

A worker process is given descriptions only, never a live simulation: it loads and caches each
configuration once (:func:`load_data`), applies the run's overrides to the configuration's data
before validation (:func:`apply_overrides`), and runs the controller on the lockstep clock, so
the same description gives the same outcome in any process. What the controller prints goes to
a file of the run's own, whose tail is kept with the result.
"""

from __future__ import annotations

import copy
import hashlib
import importlib
import json
import os
import signal
import sys
import tempfile
import time
import traceback
from collections.abc import Callable, Iterator
from contextlib import contextmanager, suppress
from dataclasses import dataclass, field
from functools import lru_cache
from pathlib import Path
from types import FrameType
from typing import Any, Literal

from simmer.config.models import SimConfig

ControllerKind = Literal["program", "policy"]
STDERR_TAIL = 800
"""Characters of a run's output kept with its result (the end: where a traceback says why)."""


@dataclass(frozen=True)
class RunSpec:
    """What one run is, as plain data: a configuration file, overrides of its keys, a seed,
    the controller and the limits. Its :meth:`key` names it in ``results.csv``."""

    config: str
    """Absolute path of the configuration file (.toml or a SimMeR config.py)."""
    overrides: tuple[tuple[str, Any], ...]
    """(dotted key, value) pairs applied to the configuration's data, in order."""
    seed: int
    kind: ControllerKind
    controller: str
    """A command line (``program``) or ``module:function`` (``policy``)."""
    folder: str
    """The sweep file's folder: the program's working directory, and where policies import from."""
    seconds: float | None = None
    """Simulated-time limit."""
    wall_seconds: float = 60.0
    """Wall-clock limit; a program's whole process tree is stopped when it passes."""
    setting: tuple[Any, ...] = field(default=(), compare=False)
    """The values of the swept keys, in the sweep's column order (for the results table)."""

    def key(self) -> str:
        """A stable hash of everything that decides the run's outcome (resume uses it)."""
        described = {
            "config": self.config,
            "overrides": [list(pair) for pair in self.overrides],
            "seed": self.seed,
            "kind": self.kind,
            "controller": self.controller,
            "seconds": self.seconds,
            "wall_seconds": self.wall_seconds,
        }
        text = json.dumps(described, sort_keys=True, separators=(",", ":"))
        return hashlib.sha256(text.encode("utf-8")).hexdigest()[:16]


@dataclass(frozen=True)
class RunResult:
    """How one run went: its outcome (``report().as_dict()``, None if there was none) and a
    ``status``: ``ok`` (the controller finished), ``error`` (it failed: non-zero exit status
    or an exception), ``seconds`` (the simulated-time limit ended it), ``timeout`` (the wall
    limit did), ``invalid`` (the overridden configuration does not validate) or ``crashed``
    (the worker process died)."""

    key: str
    status: str
    outcome: dict[str, Any] | None
    wall_time: float
    exit_status: int | None = None
    detail: str = ""
    """The tail of what the run printed (or why it could not run)."""


class LimitReached(Exception):
    """A policy ran into one of the run's limits (``seconds`` or ``timeout``)."""

    def __init__(self, status: str) -> None:
        super().__init__(status)
        self.status = status


def apply_overrides(data: dict[str, Any], overrides: tuple[tuple[str, Any], ...]) -> None:
    """Set each dotted key (``drives.w0.error.x``) in configuration data, making the tables
    on the way that are missing (a key the file left at its default); raises ``KeyError``
    if the way runs through something that is not a table."""
    for dotted, value in overrides:
        *tables, last = dotted.split(".")
        node = data
        for depth, name in enumerate(tables):
            child = node.setdefault(name, {})
            if not isinstance(child, dict):
                way = ".".join(tables[: depth + 1])
                raise KeyError(f"{dotted}: {way} is a value, not a table")
            node = child
        node[last] = copy.deepcopy(value)


@lru_cache(maxsize=8)
def load_data(path: str) -> tuple[dict[str, Any], bool]:
    """A configuration file's data before validation, and whether it is an original SimMeR
    ``config.py`` (whose data is what :func:`~simmer.config.simmer_py.read_simmer_py` maps
    its globals to). Cached: a worker reads each file once."""
    from simmer.config.loader import read_config_data

    return read_config_data(path)


@lru_cache(maxsize=64)
def _build_config(path: str, overrides_json: str) -> SimConfig:
    from simmer.config.validate import config_from_dict

    data, original = load_data(path)
    data = copy.deepcopy(data)
    apply_overrides(data, tuple((k, v) for k, v in json.loads(overrides_json)))
    return config_from_dict(data, path, Path(path).parent, original=original)


def build_config(path: str, overrides: tuple[tuple[str, Any], ...]) -> SimConfig:
    """The configuration at ``path`` with ``overrides`` applied, validated (``ConfigError``
    if the result is not a valid configuration, ``KeyError`` if an override has no place);
    cached per worker."""
    return _build_config(path, json.dumps([list(pair) for pair in overrides]))


def execute(run: RunSpec) -> RunResult:
    """Carry out one run; whatever the controller does is recorded, never raised."""
    from simmer.errors import ConfigError

    start = time.perf_counter()
    with _captured_output() as tail, _in_folder(run.folder):
        try:
            config = build_config(run.config, run.overrides)
        except (ConfigError, KeyError) as exc:
            return RunResult(
                run.key(), "invalid", None, time.perf_counter() - start, None, str(exc)
            )
        try:
            if run.kind == "program":
                status, outcome, exit_status = _run_program(run, config)
            else:
                status, outcome, exit_status = _run_policy(run, config)
        except Exception:  # the simulator itself failed: still a row, with why
            traceback.print_exc()
            status, outcome, exit_status = "error", None, None
    printed = tail() if status != "ok" else ""  # why a run failed; a finished run's chatter is not
    return RunResult(run.key(), status, outcome, time.perf_counter() - start, exit_status, printed)


def _run_program(run: RunSpec, config: SimConfig) -> tuple[str, dict[str, Any], int | None]:
    """Serve the run headless on free ports and let the program drive it."""
    from simmer.serve import serve
    from simmer.world import Simulation

    served = serve(
        Simulation(config, seed=run.seed),
        window=False,
        speed=None,
        seconds=run.seconds,
        port_rx=0,
        port_tx=0,
        stream_port=0,
        echo=lambda _line: None,
        program=run.controller,
        lockstep=True,
        timeout=run.wall_seconds,
    )
    outcome = served.outcome.report().as_dict()
    if served.ended_by == "program":
        status = "ok" if served.exit_status == 0 else "error"
        return status, outcome, served.exit_status
    return {"seconds": "seconds", "timeout": "timeout"}.get(served.ended_by, "error"), outcome, None


def _run_policy(run: RunSpec, config: SimConfig) -> tuple[str, dict[str, Any], int | None]:
    """Call ``module:function`` with a client on an in-process lockstep link."""
    from simmer.client import Client
    from simmer.world import Simulation
    from simmer.world.outcome import Outcome

    sim = Simulation(config, seed=run.seed)
    outcome = Outcome.attach(sim)
    policy = resolve_policy(run.controller, run.folder)
    link = _LimitedLink(sim, run.seconds)
    status = "ok"
    with _wall_limit(run.wall_seconds):
        try:
            policy(Client(link, lockstep=True))
        except LimitReached as limit:
            status = limit.status
        except Exception:
            traceback.print_exc()
            status = "error"
    return status, outcome.report().as_dict(), None


def resolve_policy(target: str, folder: str) -> Callable[[Any], object]:
    """The function named by ``module:function``, importing from ``folder`` first."""
    module_name, _, name = target.partition(":")
    if folder not in sys.path:
        sys.path.insert(0, folder)
    function = getattr(importlib.import_module(module_name), name)
    if not callable(function):
        raise TypeError(f"{target} is not a function")
    return function  # type: ignore[no-any-return]


class _LimitedLink:
    """A :class:`~simmer.transport.local.LocalLink` that ends the run (raising
    :class:`LimitReached`) once the simulated-time limit has passed."""

    last_text: str | None = None

    def __init__(self, sim: Any, seconds: float | None) -> None:
        from simmer.transport.local import LocalLink

        self.sim = sim
        self.inner = LocalLink(sim)
        self.seconds = seconds

    def _check(self) -> None:
        if self.seconds is not None and self.sim.time >= self.seconds - 1e-9:
            raise LimitReached("seconds")

    def exchange(self, message: str) -> list[float]:
        """Execute one message, unless the limit has passed."""
        self._check()
        return self.inner.exchange(message)

    def clock(self, message: str) -> float:
        """Send a clock message, unless the limit has passed."""
        self._check()
        return self.inner.clock(message)

    def close(self) -> None:
        """Nothing to release."""


@contextmanager
def _wall_limit(seconds: float) -> Iterator[None]:
    """Raise :class:`LimitReached` in a policy still running after ``seconds`` of wall time
    (a Python loop is interrupted; where there is no SIGALRM, nothing is)."""
    if not hasattr(signal, "setitimer"):
        yield
        return

    def expired(_signum: int, _frame: FrameType | None) -> None:
        raise LimitReached("timeout")

    previous = signal.signal(signal.SIGALRM, expired)
    signal.setitimer(signal.ITIMER_REAL, seconds)
    try:
        yield
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, previous)


@contextmanager
def _in_folder(folder: str) -> Iterator[None]:
    """Work in ``folder`` for the run (a program's relative paths are the sweep file's)."""
    before = os.getcwd()
    os.chdir(folder)
    try:
        yield
    finally:
        os.chdir(before)


@contextmanager
def _captured_output() -> Iterator[Callable[[], str]]:
    """Send this process's standard output and error (file descriptors 1 and 2, so a program
    started here and the simulator's log too) to a file of the run's own; yields what reads
    its tail once the run is over."""
    with tempfile.TemporaryFile() as capture:
        sys.stdout.flush()
        sys.stderr.flush()
        saved = os.dup(1), os.dup(2)
        os.dup2(capture.fileno(), 1)
        os.dup2(capture.fileno(), 2)
        text: list[str] = []
        try:
            yield lambda: "".join(text)
        finally:
            with suppress(ValueError, OSError):
                sys.stdout.flush()
                sys.stderr.flush()
            os.dup2(saved[0], 1)
            os.dup2(saved[1], 2)
            os.close(saved[0])
            os.close(saved[1])
            size = capture.seek(0, os.SEEK_END)
            capture.seek(max(0, size - STDERR_TAIL))
            text.append(capture.read().decode("utf-8", errors="replace").strip())
