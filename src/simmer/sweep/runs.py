"""One run of a sweep: a small picklable description (:class:`RunSpec`) and the worker that
carries it out (:func:`execute`), recording whatever happens as a :class:`RunResult`.

A worker process is given descriptions only, never a live simulation: it loads and caches each
configuration once (:func:`load_data`), applies the run's overrides to the configuration's data
before validation (:func:`apply_overrides`), keeps one simulation warm per configuration and
overrides and resets it to the run's seed (:data:`WARM`), and runs the controller on the
lockstep clock, so the same description gives the same outcome in any process and in any order.
A run changes nothing of the worker's process-wide state: a program is given its working
folder and its output (a pipe whose tail is kept with the result) when it is started; a
policy is loaded from the run's folder by file, without touching ``sys.path``, and stopped at
its wall limit by its link; only its printing is sent to the run's output while it runs.
A run to keep is recorded into a scratch folder whose files (with pictures of the first and last
frame for a failure) travel back in the result, so workers need no folder shared with the sweep.
"""

from __future__ import annotations

import copy
import hashlib
import importlib.machinery
import importlib.util
import json
import logging
import os
import signal
import sys
import tempfile
import threading
import time
import traceback
from collections import OrderedDict
from collections.abc import Callable, Iterator
from contextlib import contextmanager, redirect_stderr, redirect_stdout
from dataclasses import asdict, dataclass, field
from functools import lru_cache
from pathlib import Path
from types import FrameType, ModuleType
from typing import TYPE_CHECKING, Any, Literal

from simmer.config.models import SimConfig
from simmer.config.overrides import apply_overrides
from simmer.ending import RunEnd
from simmer.errors import LimitReached, WallLimitReached
from simmer.sweep.success import DEFAULT_SUCCESS, succeeded

if TYPE_CHECKING:
    from simmer.lockstep.box import Box, BoxLimits
    from simmer.world import Simulation

ControllerKind = Literal["program", "policy"]
Keep = Literal["nothing", "failures", "all"]
"""Which runs' folders a sweep keeps."""
STDERR_TAIL = 800
"""Characters of a run's output kept with its result (the end: where a traceback says why);
the rest is read and dropped as it comes."""
OUTPUT_GRACE = 5.0
"""Wall seconds the output's reader waits for the pipe to close after a run (a process that
escaped the run's end could hold it open: then the reader is left to finish on its own)."""
FRAME_SCALE = 2
"""A failure's first and last frames are the window's size divided by this (HUD included)."""


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
    sample: int | None = None
    """The number of the sample's draw the run is for (two draws may give the same values)."""
    success: str = DEFAULT_SUCCESS
    """The success condition (:func:`~simmer.sweep.success.success_condition`): the worker
    decides with it whether the run is a failure to keep."""
    keep: Keep = "nothing"
    """Whose files come back with the result: no run's, failures' or every run's."""
    answer: str | None = None
    """What the program reads at its prompt (``{target}``: the run's target zone)."""
    team: str | None = None
    """A graded team's name (``simmer grade``): two teams' runs differ even where their
    command lines are the same."""
    box: BoxLimits | None = None
    """Run the program in a box with these limits, in its own copy of :attr:`folder`
    (:mod:`simmer.lockstep.box`)."""

    def key(self) -> str:
        """A stable hash of everything that decides the run's outcome, and of the sample's draw
        it is for (resume uses it)."""
        described: dict[str, Any] = {
            "config": self.config,
            "overrides": [list(pair) for pair in self.overrides],
            "seed": self.seed,
            "kind": self.kind,
            "controller": self.controller,
            "seconds": self.seconds,
            "wall_seconds": self.wall_seconds,
        }
        if self.sample is not None:
            described["sample"] = self.sample
        if self.answer is not None:
            described["answer"] = self.answer
        if self.team is not None:
            described["team"] = [self.team, self.folder]
        if self.box is not None:
            described["box"] = asdict(self.box)
        text = json.dumps(described, sort_keys=True, separators=(",", ":"))
        return hashlib.sha256(text.encode("utf-8")).hexdigest()[:16]


@dataclass(frozen=True)
class RunResult:
    """How one run went: its outcome (``report().as_dict()``, None if there was none) and a
    ``status`` (:class:`~simmer.ending.RunEnd`): ``ok`` (the controller finished), ``error``
    (it failed: non-zero exit status or an exception), ``seconds`` (the simulated-time limit
    ended it), ``timeout`` (the wall limit did), ``invalid`` (the overridden configuration does
    not validate) or ``crashed`` (the worker process died); ``stopped`` (the sweep stopped
    before it began) is never recorded."""

    key: str
    status: RunEnd
    outcome: dict[str, Any] | None
    wall_time: float
    exit_status: int | None = None
    detail: str = ""
    """The tail of what the run printed (or why it could not run)."""
    success: bool = False
    files: dict[str, bytes] = field(default_factory=dict, repr=False)
    """A kept run's folder (manifest.json, events.jsonl, trace.csv, report.json, report.md),
    for a failure with first.png and last.png; a filmed run's video.mp4."""


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


class WarmSimulations:
    """The simulations a worker process keeps warm: one per configuration file and overrides
    (the last :attr:`size` used), reset to each run's seed instead of built again. A run
    takes its simulation out (:meth:`simulation`) and gives it back when it is over
    (:meth:`give_back`), so no two runs ever share one, whatever threads they run in."""

    def __init__(self, size: int = 4) -> None:
        self.size = size
        self.built = 0
        """Simulations built so far (the others were reset)."""
        self._kept: OrderedDict[tuple[str, str], Simulation] = OrderedDict()
        self._lock = threading.Lock()

    def simulation(self, run: RunSpec, config: SimConfig) -> Simulation:
        """A simulation of ``config`` (the run's configuration with its overrides) at its
        start, with the run's seed and no observers; the run's alone until given back."""
        from simmer.world import Simulation

        with self._lock:
            sim = self._kept.pop(_warm_key(run), None)
            if sim is None:
                self.built += 1
        if sim is None:
            return Simulation(config, seed=run.seed)
        sim.observers.clear()  # the last run's outcome and recorders
        sim.reset(seed=run.seed)
        return sim

    def give_back(self, run: RunSpec, sim: Simulation) -> None:
        """Keep ``sim`` warm for the next run of the same configuration and overrides."""
        with self._lock:
            self._kept[_warm_key(run)] = sim
            while len(self._kept) > self.size:
                self._kept.popitem(last=False)

    def clear(self) -> None:
        """Forget every simulation (the next run of each builds one)."""
        with self._lock:
            self._kept.clear()


def _warm_key(run: RunSpec) -> tuple[str, str]:
    return run.config, _overrides_json(run.overrides)


WARM = WarmSimulations()
"""This process's warm simulations (each run takes its own out while it runs)."""


def _overrides_json(overrides: tuple[tuple[str, Any], ...]) -> str:
    return json.dumps([list(pair) for pair in overrides])


def build_config(path: str, overrides: tuple[tuple[str, Any], ...]) -> SimConfig:
    """The configuration at ``path`` with ``overrides`` applied, validated (``ConfigError``
    if the result is not a valid configuration, ``KeyError`` if an override has no place);
    cached per worker."""
    return _build_config(path, _overrides_json(overrides))


@dataclass(frozen=True)
class _Extras:
    """Where a run is recorded and filmed (None: it is not)."""

    record: Path | None = None
    video: Path | None = None
    scratch: Path | None = None
    """The run's scratch folder (a boxed program's copy of its folder goes there)."""


def execute(run: RunSpec, *, video: bool = False) -> RunResult:
    """Carry out one run; whatever the controller does is recorded, never raised. A run to
    keep (:attr:`RunSpec.keep`) brings its folder's files back; with ``video``, the run is
    filmed instead (``video.mp4``; a failure's run again, after the sweep)."""
    from simmer.errors import ConfigError

    start = time.perf_counter()
    files: dict[str, bytes] = {}
    output = _OutputTail()
    try:
        with (
            _logged_to(output),
            tempfile.TemporaryDirectory(prefix="simmer-run-") as scratch,
        ):
            try:
                config = build_config(run.config, run.overrides)
            except (ConfigError, KeyError) as exc:
                return RunResult(
                    run.key(), RunEnd.INVALID, None, time.perf_counter() - start, None, str(exc)
                )
            keeping = run.keep != "nothing" and not video
            extras = _Extras(
                record=Path(scratch, "run") if keeping else None,
                video=Path(scratch, "video.mp4") if video else None,
                scratch=Path(scratch),
            )
            sim: Simulation | None = None
            try:
                sim = WARM.simulation(run, config)
                if keeping:
                    _follow_for_frames(sim)
                if run.kind == "program":
                    status, outcome, exit_status = _run_program(run, sim, extras, output)
                else:
                    status, outcome, exit_status = _run_policy(run, sim, extras, output)
            except Exception:  # the simulator itself failed: still a row, with why
                output.write(traceback.format_exc())
                status, outcome, exit_status = RunEnd.ERROR, None, None
            success = succeeded(run.success, outcome)
            if extras.video is not None and extras.video.exists():
                files["video.mp4"] = extras.video.read_bytes()
            if extras.record is not None and extras.record.is_dir():
                if run.keep == "all" or not success:
                    files = {p.name: p.read_bytes() for p in sorted(extras.record.iterdir())}
                if not success and outcome is not None and sim is not None:
                    files.update(_frames(sim, run.seed, output))
            if sim is not None:
                WARM.give_back(run, sim)
    finally:
        tail = output.close()
    # why a run failed; a finished run's chatter is not
    printed = tail if status is not RunEnd.OK else ""
    elapsed = time.perf_counter() - start
    return RunResult(run.key(), status, outcome, elapsed, exit_status, printed, success, files)


def film(run: RunSpec) -> RunResult:
    """Carry out one run again with a video (:func:`execute` with ``video``)."""
    return execute(run, video=True)


def _headless_pygame() -> None:
    """Let pygame draw without a display (a worker has none), and import without its banner
    (which would land in the run's output)."""
    os.environ.setdefault("SDL_VIDEODRIVER", "dummy")
    os.environ.setdefault("PYGAME_HIDE_SUPPORT_PROMPT", "1")


def _follow_for_frames(sim: Simulation) -> None:
    """Keep the path the robot drives and the last commands, for a failure's last frame to
    show."""
    from simmer.view.commands import CommandLog
    from simmer.view.trail import Trail

    sim.add_observer(Trail(sim.robot.pose))
    sim.add_observer(CommandLog())


_CANVASES: OrderedDict[int, tuple[SimConfig, Any]] = OrderedDict()
"""Off-screen renderers by configuration: a worker draws each maze's static layer once. A run
takes its renderer out while it draws (as :meth:`WarmSimulations.simulation` does)."""
_CANVASES_LOCK = threading.Lock()


def _frames(sim: Simulation, seed: int, output: _OutputTail) -> dict[str, bytes]:
    """``last.png``, the simulation as the run left it, and ``first.png``, as it started
    (after which ``sim`` is at its start again); none if they cannot be drawn."""
    try:
        _headless_pygame()
        from simmer.ui.offscreen import OffscreenRenderer
        from simmer.view.maker import LocalControls, SnapshotMaker
        from simmer.view.snapshot import StaticScene

        key = id(sim.config)
        with _CANVASES_LOCK:
            kept = _CANVASES.pop(key, None)
        kept = kept or (sim.config, OffscreenRenderer(StaticScene.of(sim)))
        canvas = kept[1]

        def picture() -> bytes:
            maker = SnapshotMaker(sim)  # the HUD shows the run's outcome, which observes sim
            try:
                canvas.invalidate()
                canvas.draw(maker.snapshot(LocalControls(sim, speed=None)))
            finally:
                maker.close()
            png: bytes = canvas.png(FRAME_SCALE)
            return png

        last = picture()
        sim.observers.clear()
        sim.reset(seed=seed)
        first = picture()
        with _CANVASES_LOCK:  # with its configuration, so that id is not reused while kept
            _CANVASES[key] = kept
            while len(_CANVASES) > WARM.size:
                _CANVASES.popitem(last=False)
        return {"first.png": first, "last.png": last}
    except Exception:  # pictures are a help; the run's row stands without them
        output.write(traceback.format_exc())
        return {}


def _run_program(
    run: RunSpec, sim: Simulation, extras: _Extras, output: _OutputTail
) -> tuple[RunEnd, dict[str, Any], int | None]:
    """Serve the run headless on free ports and let the program drive it, in the run's
    folder (relative paths are the sweep file's) and writing to the run's ``output``."""
    if extras.video is not None:
        _headless_pygame()
    answer = run.answer
    if answer is not None and sim.scenario.target is not None:
        answer = answer.replace("{target}", sim.scenario.target)
    box = None
    if run.box is not None and extras.scratch is not None:
        from simmer.lockstep.box import Box, make_box
        from simmer.lockstep.netns import Network

        work, tmp = make_box(Path(run.folder), extras.scratch)
        network = None
        if run.box.network:  # else, or where it cannot be made: the machine's (said once)
            opened = Network.open(sim.config.settings.host, [0, 0, 0])
            if isinstance(opened, str) and sys.platform.startswith("linux"):  # else: said once
                output.write(f"SimMeR box: no network of its own for this run: {opened}\n")
            network = opened if isinstance(opened, Network) else None
        box = Box(run.box, work, tmp, network)
        output.hidden.append(f"{box.work}{os.sep}")  # its traceback names robot.py, not where
    try:
        return _serve_program(run, sim, extras, output, answer, box)
    finally:
        if box is not None and box.network is not None:
            box.network.close()


def _serve_program(
    run: RunSpec,
    sim: Simulation,
    extras: _Extras,
    output: _OutputTail,
    answer: str | None,
    box: Box | None,
) -> tuple[RunEnd, dict[str, Any], int | None]:
    """Serve the run on free ports (a box's own, in its network) and let the program drive it."""
    from simmer.options import RunOptions
    from simmer.serve import serve

    options = RunOptions.free_ports(
        speed=None,
        clock="lockstep",
        seconds=run.seconds,
        program=run.controller,
        answer=answer,
        timeout=run.wall_seconds,
        program_folder=Path(run.folder),
        program_output=output.writing,
        record=extras.record,
        video=extras.video,
        box=box,
    )
    served = serve(sim, options, echo=lambda _line: None)
    if served.ended_by is RunEnd.QUIT:  # Ctrl-C or a signal stopped this worker: no result
        raise KeyboardInterrupt
    outcome = served.outcome.report().as_dict()
    program = served.ended_by is RunEnd.PROGRAM
    exit_status = served.exit_status if program else None
    return served.ended_by.as_result(exit_status), outcome, exit_status


def _run_policy(
    run: RunSpec, sim: Simulation, extras: _Extras, output: _OutputTail
) -> tuple[RunEnd, dict[str, Any], int | None]:
    """Call ``module:function`` with a client on an in-process lockstep link, what it prints
    going to the run's ``output``."""
    from simmer.client import Client
    from simmer.options import RunOptions
    from simmer.record import RunRecorder
    from simmer.world.outcome import Outcome

    policy = resolve_policy(run.controller, run.folder)
    outcome = Outcome.attach(sim)
    link = _LimitedLink(sim, run.seconds, time.monotonic() + run.wall_seconds)
    recorder = None
    if extras.record is not None:
        delay = link.inner.runner.link_delay
        options = RunOptions(speed=None, clock="lockstep", link_delay=delay, program=run.controller)
        recorder = RunRecorder(sim, extras.record, options, outcome)
    filming = None
    if extras.video is not None:
        _headless_pygame()
        from simmer.ui.video import VideoRecorder

        filming = VideoRecorder(sim, extras.video)
    status = RunEnd.OK
    try:
        with _wall_limit(run.wall_seconds), redirect_stdout(output), redirect_stderr(output):
            policy(Client(link, lockstep=True))
    except LimitReached as limit:
        status = RunEnd(limit.status)
    except Exception:
        output.write(traceback.format_exc())
        status = RunEnd.ERROR
    finally:
        if filming is not None:
            filming.close()
        if recorder is not None:
            recorder.close(status.reported)
    return status, outcome.report().as_dict(), None


_POLICY_MODULES: dict[tuple[str, str], ModuleType] = {}
"""Policy modules a worker has loaded, by folder and dotted name (each loaded once)."""
_POLICY_MODULES_LOCK = threading.Lock()


def resolve_policy(target: str, folder: str) -> Callable[[Any], object]:
    """The function named by ``module:function``, ``module`` being a file in ``folder``
    (``a.b``: ``a/b.py``)."""
    module_name, _, name = target.partition(":")
    function = getattr(_policy_module(module_name, folder), name)
    if not callable(function):
        raise TypeError(f"{target} is not a function")
    return function  # type: ignore[no-any-return]


def _policy_module(module_name: str, folder: str) -> ModuleType:
    """The module ``module_name`` found in ``folder`` only, loaded once per worker without
    changing ``sys.path``. It is kept in ``sys.modules`` under a name of its own
    (``simmer_policy_<hash>``), so two folders' modules of one name never mix and no
    module the worker imported is replaced."""
    with _POLICY_MODULES_LOCK:
        module = _POLICY_MODULES.get((folder, module_name))
        if module is not None:
            return module
        places = [folder]
        origin = None
        for part in module_name.split("."):
            spec = importlib.machinery.PathFinder.find_spec(part, places)
            if spec is None:
                raise ModuleNotFoundError(f"no module named {module_name!r} in {folder}")
            places = list(spec.submodule_search_locations or [])
            origin = spec.origin
        digest = hashlib.sha256(f"{folder}\0{module_name}".encode()).hexdigest()[:16]
        private = f"simmer_policy_{digest}"
        spec = importlib.util.spec_from_file_location(private, origin or "")
        if spec is None or spec.loader is None:
            raise ModuleNotFoundError(f"no module named {module_name!r} in {folder}")
        module = importlib.util.module_from_spec(spec)
        sys.modules[private] = module  # as an import does (dataclasses look their module up)
        try:
            spec.loader.exec_module(module)
        except ModuleNotFoundError as exc:
            del sys.modules[private]
            beside = exc.name and importlib.machinery.PathFinder.find_spec(exc.name, [folder])
            if not beside:
                raise
            raise ModuleNotFoundError(
                f"{module_name} imports {exc.name!r}, a file beside it: a policy is loaded "
                "without changing sys.path, so its imports must be installed packages; put "
                f"that code in {module_name}'s own file, or run it as a program",
                name=exc.name,
            ) from None
        except BaseException:
            del sys.modules[private]
            raise
        _POLICY_MODULES[folder, module_name] = module
        return module


class _LimitedLink:
    """A :class:`~simmer.runner.LocalLink` that ends the run (raising
    :class:`LimitReached`) once the simulated-time limit has passed, or the wall clock's
    ``deadline`` (:func:`time.monotonic`): the policy's next message ends it, in any thread."""

    last_text: str | None = None

    def __init__(self, sim: Any, seconds: float | None, deadline: float = float("inf")) -> None:
        from simmer.runner import LocalLink

        self.sim = sim
        self.inner = LocalLink(sim)
        self.seconds = seconds
        self.deadline = deadline

    def _check(self) -> None:
        if self.seconds is not None and self.sim.time >= self.seconds - 1e-9:
            raise LimitReached(RunEnd.SECONDS)
        if time.monotonic() >= self.deadline:
            raise LimitReached(RunEnd.TIMEOUT)

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
    """Raise :class:`LimitReached` (``timeout``) in a policy still running after ``seconds``
    of wall time, by SIGALRM, which interrupts a loop that never asks the simulator anything
    and a sleep too; only in the main thread (a local pool's worker runs its runs there).
    Elsewhere (a Dask worker's task thread) the run's link ends it at its next message
    (:class:`_LimitedLink`). The caller catches it outside the ``with``: the limit may pass
    as the policy returns."""
    if threading.current_thread() is not threading.main_thread() or not hasattr(
        signal, "setitimer"
    ):
        yield
        return

    def expired(_signum: int, _frame: FrameType | None) -> None:
        raise WallLimitReached

    previous = signal.signal(signal.SIGALRM, expired)
    signal.setitimer(signal.ITIMER_REAL, seconds)
    try:
        yield
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, previous)


@contextmanager
def _logged_to(output: _OutputTail) -> Iterator[None]:
    """Send the simulator's log (its warnings: what a run on a terminal would show) to the
    run's ``output`` while the run lasts."""
    handler = logging.StreamHandler(output)
    logger = logging.getLogger("simmer")
    logger.addHandler(handler)
    try:
        yield
    finally:
        logger.removeHandler(handler)


class _OutputTail:
    """A run's output, of which only the last :data:`STDERR_TAIL` characters are kept: its
    program writes to :attr:`writing` (a pipe's end, given to the program when it starts),
    which a thread reads and drops as it comes, so a program printing without end costs
    reading, not memory or disk (one wrote 3.5 GB in 8 s); the worker adds its own text
    (the simulator's log, a traceback, a policy's printing) with :meth:`write`. The pipe
    and its thread are made only for a program: with the reader alive, policy runs were
    measured a third slower here."""

    def __init__(self) -> None:
        self._pipe: tuple[int, int] | None = None
        self._thread: threading.Thread | None = None
        self._tail = bytearray()
        self._lock = threading.Lock()
        self.hidden: list[str] = []
        """Text taken out of the tail (a box's scratch folder: the same run's tail is the
        same wherever it ran)."""

    @property
    def writing(self) -> int:
        """The pipe's end a program writes to (made on first use, with its reader)."""
        if self._pipe is None:
            self._pipe = os.pipe()
            self._thread = threading.Thread(
                target=self._drain, args=(self._pipe[0],), name="simmer-output", daemon=True
            )
            self._thread.start()
        return self._pipe[1]

    def _drain(self, reading: int) -> None:
        while chunk := os.read(reading, 1 << 16):
            self._add(chunk)

    def _add(self, data: bytes) -> None:
        with self._lock:
            self._tail.extend(data)
            del self._tail[: -STDERR_TAIL * 4]  # UTF-8 takes up to 4 bytes a character

    def write(self, text: str) -> int:
        """Add ``text`` (a file's ``write``: the log handler and ``print`` call it)."""
        self._add(text.encode("utf-8", errors="replace"))
        return len(text)

    def flush(self) -> None:
        """Nothing is buffered."""

    def close(self) -> str:
        """The tail, once the pipe has ended (every process of the run is gone), or after
        :data:`OUTPUT_GRACE` seconds (one that escaped the run's end holds it open: then the
        reader is left to finish on its own)."""
        if self._pipe is not None and self._thread is not None:
            reading, writing = self._pipe
            os.close(writing)  # the program's copies are its own
            self._thread.join(OUTPUT_GRACE)
            if not self._thread.is_alive():
                os.close(reading)
        with self._lock:
            text = bytes(self._tail).decode("utf-8", errors="replace")
        for hidden in self.hidden:
            text = text.replace(hidden, "")
        return text.strip()[-STDERR_TAIL:]
