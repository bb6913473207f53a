"""``simmer run``: the simulator, with a window or headless, and a control program too.

Typer parses the flags here; :meth:`RunOptions.from_flags <simmer.options.RunOptions.from_flags>`
decides what they mean for the run, and :func:`simmer.serve.serve` serves it.
"""

from __future__ import annotations

import contextlib
import errno
import logging
import os
from collections.abc import Mapping
from enum import StrEnum
from pathlib import Path
from typing import TYPE_CHECKING, Annotated

import typer

from simmer.cli.app import AS_COMMAND, Command, app, err, example, out
from simmer.cli.common import (
    MAX_SIMULATED_SECONDS,
    ConfigArg,
    number_check,
    report_config_error,
    report_config_warnings,
)
from simmer.ending import RunEnd
from simmer.errors import ConfigError, FlagError
from simmer.options import RunOptions

if TYPE_CHECKING:
    from simmer.config import SimConfig
    from simmer.serve import Served
    from simmer.world import Simulation

MAX_WALL_SECONDS = 86_400.0
"""Largest ``--timeout``: a day, as a configuration's ``timeout`` (its ``MAX_TIMEOUT``);
longer waits overflow the system's timers."""
MAX_RECORD_LIMIT_MB = 1_048_576
"""Largest ``--record-limit``: a tebibyte, more than a lab machine's disk (infinity
overflowed the byte count)."""


class Clock(StrEnum):
    """Choices of ``--clock``."""

    realtime = "realtime"
    lockstep = "lockstep"


class LinkProtocol(StrEnum):
    """Choices of ``--protocol`` (the ``protocol`` setting): what the two-port scheme and the
    serial port speak."""

    packed = "packed"
    framed = "framed"


Headless = Annotated[bool, typer.Option("--headless", help="Run without a window.")]
Seconds = Annotated[
    float | None,
    typer.Option(
        help="Stop after this many simulated seconds.",
        metavar="SECONDS",
        callback=number_check(
            "--seconds", "seconds", MAX_SIMULATED_SECONDS, "MAX_SIMULATED_SECONDS"
        ),
    ),
]
Speed = Annotated[
    str | None,
    typer.Option(
        help="Speed as a multiple of real time (e.g. 2), or 'max' (default: 1, or max for a "
        "headless --program run). Without the lockstep clock, results at 'max' depend on "
        "the machine.",
        show_default=False,
        metavar="SPEED",
    ),
]
Seed = Annotated[
    int | None,
    typer.Option(help="Noise seed (overrides the configuration's).", metavar="N", min=0),
]
Host = Annotated[
    str | None,
    typer.Option(
        help="Address to listen on (default: the configuration's, 127.0.0.1).",
        metavar="ADDRESS",
    ),
]
PortRx = Annotated[
    int | None,
    typer.Option(
        help="SimMeR two-port scheme: message port (default: the configuration's, 61200; "
        "0: any free port).",
        min=0,
        max=65535,
        metavar="PORT",
    ),
]
PortTx = Annotated[
    int | None,
    typer.Option(
        help="SimMeR two-port scheme: reply port (default: the configuration's, 61201; "
        "0: any free port).",
        min=0,
        max=65535,
        metavar="PORT",
    ),
]
Port = Annotated[
    int | None,
    typer.Option(
        help="Persistent protocol port (default 61202; 0: any free port).",
        min=0,
        max=65535,
        metavar="PORT",
    ),
]
PortsFlag = Annotated[
    str | None,
    typer.Option(
        "--ports",
        help="All three ports at once: N (N, N+1, N+2), RX,TX,PORT, or auto (free ones, "
        "printed); default: SIMMER_PORTS if set, else the configuration's (61200, 61201, "
        "61202). --port-rx, --port-tx and --port still set one each.",
        show_default=False,
        metavar="N|RX,TX,PORT|auto",
    ),
]
Serial = Annotated[
    bool,
    typer.Option("--serial", help="Also serve a virtual serial port (a pseudo-terminal)."),
]
LidarSerial = Annotated[
    bool,
    typer.Option(
        "--lidar-serial",
        help="Also serve the robot's LiDAR as a virtual RPLidar (Slamtec's serial protocol) "
        "on a pseudo-terminal.",
    ),
]
SerialLink = Annotated[
    Path | None,
    typer.Option(help="Make a stable link to the serial port at this path.", metavar="PATH"),
]
ProtocolFlag = Annotated[
    LinkProtocol | None,
    typer.Option(
        help="What the two-port scheme and the serial port speak (default: the "
        "configuration's; a SimMeR v1.2 config.py says framed).",
        metavar="packed|framed",
    ),
]
ReplyBytes = Annotated[
    int | None,
    typer.Option(
        help="Packed reply width: 4 (SimMeR v1.1, Arduino) or 8 (v1.0) (default: the "
        "configuration's; a v1.0 config.py says 8).",
        min=4,
        max=8,
        metavar="4|8",
    ),
]
ProgramFlag = Annotated[
    str | None,
    typer.Option(
        help='Start this control program (e.g. "python my_robot.py") on free ports and '
        "end the run when it exits; its clock follows simulated time (lockstep). It runs as "
        "written, in your environment: python is the first on your PATH (Python 3.8 or "
        "later), with your packages. SimMeR adds its lockstep shim first on PYTHONPATH, "
        "SIMMER_* variables (this run's ports) and PYTHONUNBUFFERED=1. A process the "
        "program starts may not sleep or talk to the simulator.",
        show_default=False,
        metavar="COMMAND",
    ),
]
ClockFlag = Annotated[
    Clock | None,
    typer.Option(
        help="realtime: simulated time follows the wall clock; lockstep: it advances only "
        "when the program sleeps (and per message), so runs repeat exactly (default: "
        "lockstep with --program, else realtime).",
        show_default=False,
        metavar="realtime|lockstep",
    ),
]
LinkDelay = Annotated[
    float | None,
    typer.Option(
        help="Lockstep: simulated seconds each message costs (default: one step).",
        callback=number_check(
            "--link-delay", "seconds", MAX_SIMULATED_SECONDS, "MAX_SIMULATED_SECONDS", zero=True
        ),
        show_default=False,
        metavar="SECONDS",
    ),
]
Timeout = Annotated[
    float | None,
    typer.Option(
        help="Stop the run (and the program's whole process tree) after this many "
        "wall-clock seconds; exit status 124.",
        callback=number_check("--timeout", "seconds", MAX_WALL_SECONDS, "MAX_WALL_SECONDS"),
        show_default=False,
        metavar="SECONDS",
    ),
]
Record = Annotated[
    Path | None,
    typer.Option(
        help="Record the run into this folder (a new one): manifest.json, events.jsonl, "
        "trace.csv, report.json and report.md.",
        show_default=False,
        metavar="DIR",
    ),
]
Video = Annotated[
    Path | None,
    typer.Option(
        help="Record what the window shows into this .mp4 (H.264) or .gif file, at 30 "
        "frames per simulated second, with or without a window; an existing file is kept "
        "unless --force.",
        show_default=False,
        metavar="FILE",
    ),
]
Force = Annotated[bool, typer.Option("--force", help="Let --video replace an existing file.")]
Start = Annotated[
    str | None,
    typer.Option(
        help="Project: where the robot starts: a cell 'row,col' or 'row,col,heading', "
        "'random' (a start cell drawn from the seed), 'open' or 'config'.",
        show_default=False,
        metavar="CELL",
    ),
]
Block = Annotated[
    str | None,
    typer.Option(
        help="Project: the block's centre 'x,y' in inches, 'random' (inside the loading "
        "zone, drawn from the seed) or 'config'.",
        show_default=False,
        metavar="X,Y",
    ),
]
Target = Annotated[
    str | None,
    typer.Option(
        help="Project: the drop-off zone to deliver to (e.g. B2), or 'random'.",
        show_default=False,
        metavar="ZONE",
    ),
]
Answer = Annotated[
    str | None,
    typer.Option(
        help='What --program reads at its input() prompt (e.g. the target zone, "B2"); '
        "'{target}' is replaced by this run's target.",
        show_default=False,
        metavar="TEXT",
    ),
]
RecordLimit = Annotated[
    float,
    typer.Option(
        help="Megabytes events.jsonl and trace.csv of --record may hold together; past it "
        "the recording stops and the run goes on.",
        callback=number_check(
            "--record-limit", "MB", MAX_RECORD_LIMIT_MB, "MAX_RECORD_LIMIT_MB", zero=True, low=1
        ),
    ),
]


@app.command(
    cls=Command,
    short_help="Run the simulator: a window, or headless; your program too.",
    epilog=example('simmer run my_rover.toml --headless --program "python dead_reckoning.py"'),
)
def run(
    config: ConfigArg = None,
    headless: Headless = False,
    seconds: Seconds = None,
    speed: Speed = None,
    seed: Seed = None,
    host: Host = None,
    port_rx: PortRx = None,
    port_tx: PortTx = None,
    port: Port = None,
    ports: PortsFlag = None,
    serial: Serial = False,
    serial_link: SerialLink = None,
    lidar_serial: LidarSerial = False,
    protocol: ProtocolFlag = None,
    reply_bytes: ReplyBytes = None,
    program: ProgramFlag = None,
    clock: ClockFlag = None,
    link_delay: LinkDelay = None,
    timeout: Timeout = None,
    record: Record = None,
    video: Video = None,
    force: Force = False,
    start: Start = None,
    block: Block = None,
    target: Target = None,
    answer: Answer = None,
    record_limit: RecordLimit = 256,
) -> None:
    """Run the simulator on CONFIG (default: the built-in lab maze and rover). With --program,
    the run ends when the program exits (with its exit status), at --seconds of simulated time
    (status 3) or at --timeout wall seconds (status 124)."""
    try:
        options = RunOptions.from_flags(
            headless=headless,
            speed=speed,
            clock=clock,
            program=program,
            answer=answer,
            port_rx=port_rx,
            port_tx=port_tx,
            port=port,
            ports=ports,
            serial=serial,
            serial_link=serial_link,
            lidar_serial=lidar_serial,
            link_delay=link_delay,
            seconds=seconds,
            timeout=timeout,
            record=record,
            record_limit_mb=record_limit,
            video=video,
        )
    except FlagError as exc:
        raise typer.BadParameter(exc.message, param_hint=exc.flag) from None
    if video is not None:
        _check_video(video, force=force)
    settings = {"protocol": protocol and protocol.value, "reply_bytes": reply_bytes, "host": host}
    loaded = _run_config(config, {**settings, **options.ports.settings()}, start, block, target)
    sim = _run_simulation(loaded, seed)
    raise typer.Exit(_serve(sim, _recorded(options.for_target(sim.scenario.target))))


def _serve(sim: Simulation, options: RunOptions) -> int:
    """Serve the run (its program's detached children kept in sight, the simulator's log in a
    file of its own beside a program), say how it went, and give its exit status."""
    from simmer.errors import SimmerError
    from simmer.serve import serve

    if options.program is not None and AS_COMMAND:  # its detached children stay in sight
        from simmer.proctree import adopt_orphans  # (not when embedded: simmer.proctree)

        adopt_orphans()
    run_log = _RunLog() if options.program is not None else None
    if run_log is not None:
        out.print(f"the simulator's log goes to {run_log.path} (kept if it warns)", markup=False)
    try:
        served = serve(sim, options, echo=lambda line: out.print(line, markup=False))
    except SimmerError as exc:
        err.print(str(exc), style="bold red")
        raise typer.Exit(1) from None
    except OSError as exc:
        err.print(_serve_failure(exc, sim.config.settings.host), style="bold red", markup=False)
        raise typer.Exit(1) from None
    finally:
        log_file = run_log.finish() if run_log is not None else None
    _say_how_it_went(served, options, log_file)
    return served.exit_status


def _recorded(options: RunOptions) -> RunOptions:
    """The options with ``--record``'s folder ready before any port opens (one that cannot
    be used is the whole message, exit status 1) and a recorded run's limits."""
    if options.record is None:
        return options
    from simmer.record.runfolder import prepare_folder

    try:
        prepare_folder(options.record)
    except OSError as exc:
        err.print(f"cannot record into {options.record}: {exc}", style="bold red", markup=False)
        raise typer.Exit(1) from None
    seconds, timeout = _recorded_run_limits(options.seconds, options.timeout, options.program)
    return options.replace(seconds=seconds, timeout=timeout)


def _run_config(
    config: Path | None, overrides: Mapping[str, object], *scenario: str | None
) -> SimConfig:
    """The run's configuration: the file, the command line's settings checked as the file's
    own are (two equal ports are refused before any port opens), then ``--start``,
    ``--block`` and ``--target``; a mistake is reported and ends the command."""
    from simmer.config import load_config, with_overrides

    given = {key: value for key, value in overrides.items() if value is not None}
    if given.get("reply_bytes") not in (None, 4, 8):
        raise typer.BadParameter("4 or 8", param_hint="--reply-bytes")
    flags = " ".join(f"--{key.replace('_', '-')} {value}" for key, value in given.items())
    try:
        loaded = load_config(config)
        if given:
            loaded = with_overrides(loaded, given, f"{loaded.source} with {flags}")
    except ConfigError as exc:
        report_config_error(exc)
        raise typer.Exit(1) from None
    start, block, target = scenario
    return _with_scenario(loaded, start=start, block=block, target=target)


def _run_simulation(loaded: SimConfig, seed: int | None) -> Simulation:
    """The simulation of ``loaded`` (a device that fails to build is reported as `check`
    reports it), and the start-up lines: warnings, the release, the summary, the scenario."""
    from simmer.config import summarize
    from simmer.config.zones import project_run
    from simmer.world import Simulation

    try:
        sim = Simulation(loaded, seed=seed)
    except Exception:  # a device's own constructor: say which, as `check` does
        from simmer.world.probe import probe_devices

        report_config_error(ConfigError(loaded.source, probe_devices(loaded)))
        raise typer.Exit(1) from None
    report_config_warnings(loaded)
    if loaded.origin:
        out.print(loaded.origin, markup=False)
    out.print(summarize(sim.config, seed=sim.seed), markup=False)
    if project_run(loaded):
        out.print(f"scenario: {sim.scenario.describe()}", markup=False)
    return sim


def _say_how_it_went(served: Served, options: RunOptions, log_file: Path | None) -> None:
    """The outcome, where the recording is, and (with a program) why the run ended and where
    the simulator's log is, if it was kept (``log_file``)."""
    out.print(served.outcome.report().summary(), markup=False)
    if served.recording_stopped is not None:
        err.print(served.recording_stopped, style="bold red", markup=False)
    elif options.record is not None:
        report = options.record / "report.md"
        out.print(f"recorded in {options.record}; the report is {report}", markup=False)
    if options.program is not None:
        match served.ended_by:
            case RunEnd.PROGRAM:
                ended = f"the program exited with status {served.program_status}"
            case RunEnd.SECONDS:
                ended = f"the limit of {options.seconds} s of simulated time was reached"
            case RunEnd.TIMEOUT:
                ended = (
                    f"the {options.timeout} s wall-clock timeout was reached; "
                    "the program was stopped"
                )
            case _:
                ended = "the run was stopped"
        log = (
            "the simulator's log had no warnings and is removed"
            if log_file is None
            else f"the simulator's log has warnings: {log_file}"
        )
        out.print(f"run ended: {ended}; {log}", markup=False)


def _with_scenario(config: SimConfig, **parts: str | None) -> SimConfig:
    """The configuration with --start, --block and --target in its [scenario] (so the manifest
    and a replay have them); a part that cannot be met is one plain line and exit status 1."""
    from simmer.config import with_overrides

    given = {key: value for key, value in parts.items() if value is not None}
    if not given:
        return config
    try:
        return with_overrides(config, {f"scenario.{key}": value for key, value in given.items()})
    except ConfigError as exc:
        for issue in exc.issues:
            part = issue.key.removeprefix("scenario.")
            where = f"--{part}" if part in given else issue.key
            err.print(f"{where}: {issue.message}", style="bold red", markup=False)
        raise typer.Exit(1) from None


def _recorded_run_limits(
    seconds: float | None, timeout: float | None, program: str | None
) -> tuple[float, float | None]:
    """A recorded run's limits: ``--seconds`` (default: an hour of simulated time) and, with
    a program, ``--timeout`` (default: an hour of wall time), so that a program that sleeps or
    hangs forever does not record forever."""
    from simmer.record.runfolder import MAX_RUN_SECONDS

    if seconds is None:
        seconds = MAX_RUN_SECONDS
        out.print(
            f"a recorded run stops at {seconds:g} s of simulated time (--seconds changes it)",
            markup=False,
        )
    if program is not None and timeout is None:
        timeout = MAX_RUN_SECONDS
        out.print(
            f"a recorded program is stopped after {timeout:g} s of wall time "
            "(--timeout changes it)",
            markup=False,
        )
    return seconds, timeout


def _check_video(path: Path, *, force: bool) -> None:
    """Refuse a video file that cannot be written, or that exists unless ``force``, before any
    port opens; make its folder if it is missing (as --record does: ``--video runs/task1.mp4``
    in a new project)."""
    from simmer.view.frames import check_video_path

    try:
        check_video_path(path)
    except ValueError as exc:
        raise typer.BadParameter(str(exc), param_hint="--video") from None
    if path.exists() and not force:
        err.print(
            f"the video {path} exists already: give another name, or add --force to replace it",
            style="bold red",
            markup=False,
        )
        raise typer.Exit(1)
    folder = path.parent
    with contextlib.suppress(OSError):  # said just below, as for a folder not writable
        folder.mkdir(parents=True, exist_ok=True)
    if not folder.is_dir() or not os.access(folder, os.W_OK):
        err.print(
            f"cannot write the video {path}: no writable folder {folder}",
            style="bold red",
            markup=False,
        )
        raise typer.Exit(1)


class _RunLog:
    """The simulator's log during a ``--program`` run (Python's warnings too), in a file of its
    own so that the program's printout is not mixed with it. The file is made by
    :func:`tempfile.mkstemp`: a name nobody can know beforehand, created only if nothing is
    there (the old ``simmer-PID.log`` followed a link planted at that name, and one was left
    per run). It is removed when the run ends unless it holds a warning or an error
    (:meth:`finish`)."""

    def __init__(self) -> None:
        import tempfile

        descriptor, name = tempfile.mkstemp(prefix="simmer-", suffix=".log")
        self.path = Path(name)
        self.worth_keeping = False
        """A warning or an error was logged."""
        self._file = open(descriptor, "w", encoding="utf-8")  # noqa: SIM115 (closed in finish)
        self._handler = logging.StreamHandler(self._file)
        self._handler.setFormatter(
            logging.Formatter("%(asctime)s %(levelname)s %(name)s: %(message)s")
        )
        self._handler.addFilter(self._note)
        root = logging.getLogger()
        self._previous = list(root.handlers)
        for old in self._previous:
            root.removeHandler(old)
        root.addHandler(self._handler)
        logging.captureWarnings(True)  # a library's warning too: not in the program's printout

    def _note(self, record: logging.LogRecord) -> bool:
        if record.levelno >= logging.WARNING:
            self.worth_keeping = True
        return True

    def finish(self) -> Path | None:
        """Close the file and give the log back to where it went before; the file if it is
        kept (it holds a warning or an error), else None (it is removed)."""
        logging.captureWarnings(False)
        root = logging.getLogger()
        root.removeHandler(self._handler)
        for old in self._previous:
            root.addHandler(old)
        self._file.close()
        if self.worth_keeping:
            return self.path
        with contextlib.suppress(OSError):
            self.path.unlink()
        return None


def _serve_failure(exc: OSError, host: str) -> str:
    """Why the simulator could not listen, pointing at the fix (only a port in use can mean
    another simmer)."""
    if exc.errno == errno.EADDRINUSE:
        return (
            f"cannot serve: {exc}. Another simmer run (or another program) is using this port: "
            "close it, or choose other ports: --ports 62000 (62000-62002), --ports auto, or "
            "SIMMER_PORTS=62000 in this terminal's environment"
        )
    if ":" in host:  # an IPv6 address, and the servers listen on IPv4 (AF_INET) sockets
        return (
            f"cannot serve on '{host}': SimMeR listens on IPv4 addresses only; use --host "
            "127.0.0.1 (this machine) or --host 0.0.0.0 (every network). The system said: "
            f"{exc.strerror or exc}"
        )
    if exc.errno == errno.EADDRNOTAVAIL:
        return (
            f"cannot serve on '{host}': not an address of this machine ({exc.strerror}); "
            "use --host 127.0.0.1 (this machine) or --host 0.0.0.0 (every network)"
        )
    return f"cannot serve: {exc}"
