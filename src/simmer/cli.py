"""The ``simmer`` command: run a simulation, check a configuration, and more."""

from __future__ import annotations

import contextlib
import errno
import logging
import os
from collections.abc import Callable, Iterator, Mapping
from enum import StrEnum
from pathlib import Path
from typing import TYPE_CHECKING, Annotated, NoReturn

import typer
from rich.console import Console
from rich.text import Text
from typer import _click  # the click typer ships: its Command is what a command overrides
from typer.core import TyperArgument, TyperCommand, TyperGroup, TyperOption

from simmer.errors import ConfigError, ExitCalled
from simmer.ports import STREAM_PORT

if TYPE_CHECKING:
    from simmer.config import SimConfig
    from simmer.options import RunOptions
    from simmer.serve import Served
    from simmer.view.replay_model import Recording
    from simmer.world import Simulation


class _Command(TyperCommand):
    """A command whose help shows arguments as ``CONFIG`` / ``[CONFIG]`` with their help, as
    click does (typer writes ``{config}`` and ``<path>``)."""

    def collect_usage_pieces(self, ctx: _click.Context) -> list[str]:
        """``[OPTIONS] CONFIG``: an optional argument in brackets, a required one bare."""
        pieces = [self.options_metavar] if self.options_metavar else []
        for param in self.get_params(ctx):
            if isinstance(param, TyperArgument):
                name = _argument_name(param)
                pieces.append(name if param.required else f"[{name}]")
        return pieces

    def format_options(self, ctx: _click.Context, formatter: _click.HelpFormatter) -> None:
        """The arguments by name and help, then the options as typer writes them."""
        params = self.get_params(ctx)
        rows = [(_argument_name(p), p.help or "") for p in params if isinstance(p, TyperArgument)]
        options = [
            record
            for p in params
            if not isinstance(p, TyperArgument) and (record := p.get_help_record(ctx))
        ]
        for title, entries in (("Arguments", rows), ("Options", options)):
            if entries:
                with formatter.section(title):
                    formatter.write_dl(entries)


def _argument_name(param: TyperArgument) -> str:
    return param.metavar or (param.name or "").upper()


class _Group(TyperGroup):
    """The ``simmer`` group, whose ``--help`` costs nothing when a command is run."""

    def get_help_option(self, ctx: _click.Context) -> TyperOption | None:
        """The help option, "not given" being False: typer coerces a value that is not a bool
        through pydantic, and building that for ``simmer run --help`` took 50 ms and 14 MB."""
        option = super().get_help_option(ctx)
        if option is not None:
            option.default = False
        return option


app = typer.Typer(
    name="simmer",
    cls=_Group,
    help="SimMeR, the Simulator for Mechatronics Robots.",
    no_args_is_help=False,
    add_completion=False,
    pretty_exceptions_enable=False,
    rich_markup_mode=None,  # help as written: [u0] stays, no boxes, no <bool>
)
_AS_COMMAND: list[bool] = []
"""Holds True when this process is the ``simmer`` command (:func:`main`), not a program that
calls the app (a test): only then does ``run --program`` make it a subreaper."""
out = Console(markup=False, emoji=False, highlight=False, soft_wrap=True)
err = Console(stderr=True, markup=False, emoji=False, highlight=False, soft_wrap=True)
"""What the command prints is data (paths, messages, keys, a program's output): neither markup
(``[b]``) nor emoji codes (``:100:`` of ``robot.toml:100:``) are applied to it; a colour is a
``style``."""


MAX_SIMULATED_SECONDS = 1e9
"""Largest ``--seconds`` and ``--link-delay``: the longest ``!sleep`` (a command's
``MAX_ABS_VALUE``), some 30 years of simulated time; NaN, infinities and negative numbers
are refused too (``--seconds nan`` ran no step and reported success)."""
SPEED_RANGE = (0.01, 1000.0)
"""``--speed`` as a multiple of real time, 'max' aside: the window's keys go from 1/8 to 32; a
speed of 1e-300 never took a second step, and above 1,000 only 'max' is faster."""
MAX_WALL_SECONDS = 86_400.0
"""Largest ``--timeout``: a day, as a configuration's ``timeout`` (its ``MAX_TIMEOUT``);
longer waits overflow the system's timers."""
MAX_WORKERS = 64
"""Largest ``sweep --workers``: each worker process holds some 256 MB, so 64 of them hold
16 GB, more than a lab machine has, and more workers than cores only wait their turn (a pool
of 10**6 would start a process for each run of a sweep, up to 100,000)."""
MAX_RECORD_LIMIT_MB = 1_048_576
"""Largest ``--record-limit``: a tebibyte, more than a lab machine's disk (infinity
overflowed the byte count)."""


def _number_check(
    flag: str, unit: str, high: float, limit: str, *, zero: bool = False, low: float = 0.0
) -> Callable[[float | None], float | None]:
    """A numeric flag's check, run before the number is used: finite, more than ``low`` (or
    equal to it with ``zero``) and at most ``high`` (the constant named ``limit``); else one
    plain line saying so."""

    def check(value: float | None) -> float | None:
        if value is None or ((low <= value if zero else low < value) and value <= high):
            return value  # NaN fails both comparisons
        least = f"{low:g} or more" if zero else f"more than {low:g}"
        raise typer.BadParameter(
            f"{value!r} {unit}; give a number {least} and at most {high:,.0f} ({limit}; "
            "SimMeR's limits are in docs/limits.md)",
            param_hint=flag,
        )

    return check


class Clock(StrEnum):
    """Choices of ``--clock``."""

    realtime = "realtime"
    lockstep = "lockstep"


class Protocol(StrEnum):
    """Choices of ``--protocol`` (the ``protocol`` setting)."""

    packed = "packed"
    framed = "framed"


ConfigArg = Annotated[
    Path | None,
    typer.Argument(
        help="Configuration file (.toml, or a SimMeR config.py). Default: the built-in lab maze "
        "and rover.",
        show_default=False,
        metavar="CONFIG",
    ),
]
RunFolder = Annotated[
    Path, typer.Argument(help="A run folder (simmer run --record DIR).", metavar="DIR")
]


def _example(*lines: str) -> str:
    """A help page's example block, printed as written (click does not re-wrap a paragraph
    that starts with \\b)."""
    return "\b\nExample:\n" + "\n".join(f"  {line}" for line in lines)


def _print_version(wanted: bool) -> None:
    """``--version``: print the installed package's version and stop."""
    if wanted:
        from importlib.metadata import PackageNotFoundError, version

        try:
            out.print(f"simmer {version('simmer')}", markup=False)
        except PackageNotFoundError:  # run from a source tree without installing
            out.print("simmer (version unknown: not installed; pip install -e .)", markup=False)
        raise typer.Exit()


@app.callback()
def options(
    show_version: Annotated[
        bool,
        typer.Option(
            "--version",
            help="Print SimMeR's version and exit.",
            callback=_print_version,
            is_eager=True,
        ),
    ] = False,
) -> None:
    """SimMeR, the Simulator for Mechatronics Robots."""


def _report_config_error(exc: ConfigError) -> None:
    count = len(exc.issues)
    err.print(f"{count} problem{'s' if count != 1 else ''} in {exc.source}:", style="bold red")
    for issue in exc.issues:
        err.print(f"  {issue.render(exc.source)}", markup=False)


def _report_config_warnings(config: SimConfig) -> None:
    """Print what an original config.py does that a native file may not (it still runs)."""
    count = len(config.warnings)
    if count:
        err.print(
            f"{count} warning{'s' if count != 1 else ''} in {config.source}:", style="bold yellow"
        )
    for issue in config.warnings:
        err.print(f"  {issue.render(config.source)}", markup=False, style="yellow")


@app.command(
    cls=_Command,
    short_help="Make a folder of your own for Lab 1 (rover, programs, sweeps).",
    epilog=_example("simmer new lab1", "cd lab1", "simmer check my_rover.toml"),
)
def new(
    folder: Annotated[
        Path, typer.Argument(help="The folder to make (new, or empty).", metavar="DIR")
    ],
) -> None:
    """Make a folder of your own for Lab 1: the lab's rover (my_rover.toml), the example
    programs, two sweep files and a README pointing at the lab page, whose every command runs
    from this folder."""
    from simmer.errors import FolderExists
    from simmer.newfolder import lab_page, new_folder

    try:
        written = new_folder(folder)
    except (FolderExists, OSError) as exc:
        err.print(f"cannot make the folder: {exc}", style="bold red", markup=False)
        raise typer.Exit(1) from None
    out.print(f"made {folder}: {', '.join(path.name for path in written)}", markup=False)
    out.print(
        f"next: cd {folder}, then simmer check my_rover.toml; the lab page: {lab_page()}",
        markup=False,
    )


@app.command(
    cls=_Command,
    short_help="Check a configuration: OK and a summary, or every problem.",
    epilog=_example("simmer check my_rover.toml"),
)
def check(
    config: Annotated[Path, typer.Argument(help="Configuration file to check.", metavar="CONFIG")],
) -> None:
    """Check a configuration and call each device once: print OK and a summary, or every
    problem found, each with its file, line, key and fix (exit status 1)."""
    from simmer.config import load_config, summarize
    from simmer.config.loader import placed_issues

    with _exit_refused():
        try:
            loaded = load_config(config)
        except ConfigError as exc:
            _report_config_error(exc)
            raise typer.Exit(1) from None
        _report_config_warnings(loaded)
        if loaded.origin:
            out.print(loaded.origin, markup=False)
        from simmer.world.probe import probe_devices

        issues = probe_devices(loaded)
    if issues:
        _report_config_error(ConfigError(config, placed_issues(config, issues)))
        raise typer.Exit(1)
    out.print(Text.assemble(("OK", "bold green"), f" {config}"))
    out.print(summarize(loaded), markup=False)


@contextlib.contextmanager
def _exit_refused() -> Iterator[None]:
    """Within ``with``: ``os._exit(n)`` raises :class:`ExitCalled` (a ``SystemExit``, which
    check reports as a plug-in's or device's problem) instead of ending the process with no
    word: the code ``check`` imports and calls is the user's."""
    real = os._exit

    def refused(status: int) -> NoReturn:
        raise ExitCalled(f"os._exit({status}) was called")

    os._exit = refused
    try:
        yield
    finally:
        os._exit = real


@app.command(
    cls=_Command,
    short_help="List every configuration key and device setting.",
    epilog=_example("simmer keys --markdown > keys.md"),
)
def keys(
    markdown: Annotated[
        bool, typer.Option("--markdown", help="Print the reference as Markdown.")
    ] = False,
) -> None:
    """List every configuration key and device setting, with defaults."""
    from simmer.config.reference import reference_markdown

    text = reference_markdown()
    if markdown:
        print(text, end="")
    else:  # the note for whoever maintains docs/configuration.md is not for a terminal
        from rich.markdown import Markdown

        lines = [line for line in text.splitlines() if "do not edit by hand" not in line]
        out.print(Markdown("\n".join(lines)))


@app.command(
    cls=_Command,
    short_help="Run the simulator: a window, or headless; your program too.",
    epilog=_example('simmer run my_rover.toml --headless --program "python dead_reckoning.py"'),
)
def run(
    config: ConfigArg = None,
    headless: Annotated[bool, typer.Option("--headless", help="Run without a window.")] = False,
    seconds: Annotated[
        float | None,
        typer.Option(
            help="Stop after this many simulated seconds.",
            metavar="SECONDS",
            callback=_number_check(
                "--seconds", "seconds", MAX_SIMULATED_SECONDS, "MAX_SIMULATED_SECONDS"
            ),
        ),
    ] = None,
    speed: Annotated[
        str | None,
        typer.Option(
            help="Speed as a multiple of real time (e.g. 2), or 'max' (default: 1, or max for a "
            "headless --program run). Without the lockstep clock, results at 'max' depend on "
            "the machine.",
            show_default=False,
            metavar="SPEED",
        ),
    ] = None,
    seed: Annotated[
        int | None,
        typer.Option(help="Noise seed (overrides the configuration's).", metavar="N", min=0),
    ] = None,
    host: Annotated[
        str | None,
        typer.Option(
            help="Address to listen on (default: the configuration's, 127.0.0.1).",
            metavar="ADDRESS",
        ),
    ] = None,
    port_rx: Annotated[
        int | None,
        typer.Option(
            help="SimMeR two-port scheme: message port (default: the configuration's, 61200; "
            "0: any free port).",
            min=0,
            max=65535,
            metavar="PORT",
        ),
    ] = None,
    port_tx: Annotated[
        int | None,
        typer.Option(
            help="SimMeR two-port scheme: reply port (default: the configuration's, 61201; "
            "0: any free port).",
            min=0,
            max=65535,
            metavar="PORT",
        ),
    ] = None,
    port: Annotated[
        int | None,
        typer.Option(
            help="Persistent protocol port (default 61202; 0: any free port).",
            min=0,
            max=65535,
            metavar="PORT",
        ),
    ] = None,
    serial: Annotated[
        bool,
        typer.Option("--serial", help="Also serve a virtual serial port (a pseudo-terminal)."),
    ] = False,
    serial_link: Annotated[
        Path | None,
        typer.Option(help="Make a stable link to the serial port at this path.", metavar="PATH"),
    ] = None,
    protocol: Annotated[
        Protocol | None,
        typer.Option(
            help="What the two-port scheme and the serial port speak (default: the "
            "configuration's; a SimMeR v1.2 config.py says framed).",
            metavar="packed|framed",
        ),
    ] = None,
    reply_bytes: Annotated[
        int | None,
        typer.Option(
            help="Packed reply width: 4 (SimMeR v1.1, Arduino) or 8 (v1.0) (default: the "
            "configuration's; a v1.0 config.py says 8).",
            min=4,
            max=8,
            metavar="4|8",
        ),
    ] = None,
    program: Annotated[
        str | None,
        typer.Option(
            help='Start this control program (e.g. "python my_robot.py") on free ports and '
            "end the run when it exits; its clock follows simulated time (lockstep).",
            show_default=False,
            metavar="COMMAND",
        ),
    ] = None,
    clock: Annotated[
        Clock | None,
        typer.Option(
            help="realtime: simulated time follows the wall clock; lockstep: it advances only "
            "when the program sleeps (and per message), so runs repeat exactly (default: "
            "lockstep with --program, else realtime).",
            show_default=False,
            metavar="realtime|lockstep",
        ),
    ] = None,
    link_delay: Annotated[
        float | None,
        typer.Option(
            help="Lockstep: simulated seconds each message costs (default: one step).",
            callback=_number_check(
                "--link-delay", "seconds", MAX_SIMULATED_SECONDS, "MAX_SIMULATED_SECONDS", zero=True
            ),
            show_default=False,
            metavar="SECONDS",
        ),
    ] = None,
    timeout: Annotated[
        float | None,
        typer.Option(
            help="Stop the run (and the program's whole process tree) after this many "
            "wall-clock seconds; exit status 124.",
            callback=_number_check("--timeout", "seconds", MAX_WALL_SECONDS, "MAX_WALL_SECONDS"),
            show_default=False,
            metavar="SECONDS",
        ),
    ] = None,
    record: Annotated[
        Path | None,
        typer.Option(
            help="Record the run into this folder (a new one): manifest.json, events.jsonl, "
            "trace.csv, report.json and report.md.",
            show_default=False,
            metavar="DIR",
        ),
    ] = None,
    video: Annotated[
        Path | None,
        typer.Option(
            help="Record what the window shows into this .mp4 (H.264) or .gif file, at 30 "
            "frames per simulated second, with or without a window; an existing file is kept "
            "unless --force.",
            show_default=False,
            metavar="FILE",
        ),
    ] = None,
    force: Annotated[
        bool, typer.Option("--force", help="Let --video replace an existing file.")
    ] = False,
    start: Annotated[
        str | None,
        typer.Option(
            help="Project: where the robot starts: a cell 'row,col' or 'row,col,heading', "
            "'random' (a start cell drawn from the seed), 'open' or 'config'.",
            show_default=False,
            metavar="CELL",
        ),
    ] = None,
    block: Annotated[
        str | None,
        typer.Option(
            help="Project: the block's centre 'x,y' in inches, 'random' (inside the loading "
            "zone, drawn from the seed) or 'config'.",
            show_default=False,
            metavar="X,Y",
        ),
    ] = None,
    target: Annotated[
        str | None,
        typer.Option(
            help="Project: the drop-off zone to deliver to (e.g. B2), or 'random'.",
            show_default=False,
            metavar="ZONE",
        ),
    ] = None,
    answer: Annotated[
        str | None,
        typer.Option(
            help='What --program reads at its input() prompt (e.g. the target zone, "B2"); '
            "'{target}' is replaced by this run's target.",
            show_default=False,
            metavar="TEXT",
        ),
    ] = None,
    record_limit: Annotated[
        float,
        typer.Option(
            help="Megabytes events.jsonl and trace.csv of --record may hold together; past it "
            "the recording stops and the run goes on.",
            callback=_number_check(
                "--record-limit", "MB", MAX_RECORD_LIMIT_MB, "MAX_RECORD_LIMIT_MB", zero=True, low=1
            ),
        ),
    ] = 256,
) -> None:
    """Run the simulator on CONFIG (default: the built-in lab maze and rover).

    With --program, the run ends when the program exits (with its exit status), at --seconds
    of simulated time (status 3) or at --timeout wall seconds (status 124).
    """
    from simmer.serve import parse_speed

    lockstep = (clock or (Clock.lockstep if program else Clock.realtime)) == Clock.lockstep
    if speed is None:
        speed = "max" if headless and program else "1"
    try:
        pace = parse_speed(speed)
    except ValueError as exc:
        raise typer.BadParameter(str(exc), param_hint="--speed") from None
    low, high = SPEED_RANGE
    if pace is not None and not low <= pace <= high:
        raise typer.BadParameter(
            f"{speed}: from {low:g} to {high:g} times real time, or 'max' (SPEED_RANGE; "
            "SimMeR's limits are in docs/limits.md)",
            param_hint="--speed",
        )
    if video is not None:
        _check_video(video, force=force)
    if program is not None:  # this run's own free ports, so that runs can share a machine
        port_rx = 0 if port_rx is None else port_rx
        port_tx = 0 if port_tx is None else port_tx
        port = 0 if port is None else port
    if reply_bytes not in (None, 4, 8):
        raise typer.BadParameter("4 or 8", param_hint="--reply-bytes")
    if answer is not None and program is None:
        raise typer.BadParameter("what --program reads at its prompt: give --program too")
    from simmer.lockstep import MAX_ANSWER

    if answer is not None and len(answer) > MAX_ANSWER:
        raise typer.BadParameter(
            f"{len(answer):,} characters; at most {MAX_ANSWER:,} (a few typed lines)",
            param_hint="--answer",
        )
    overrides = {  # into the configuration, so that the start-up summary shows what is used
        "protocol": protocol and protocol.value,
        "reply_bytes": reply_bytes,
        "host": host,
        "port_rx": port_rx or None,  # 0 is no setting: the transport lines say which port
        "port_tx": port_tx or None,
    }
    loaded = _run_config(config, overrides, start=start, block=block, target=target)
    sim = _run_simulation(loaded, seed)
    if answer is not None and sim.scenario.target is not None:
        answer = answer.replace("{target}", sim.scenario.target)
    from simmer.errors import SimmerError
    from simmer.options import RunOptions
    from simmer.serve import serve

    if record is not None:
        from simmer.record.runfolder import prepare_folder

        try:  # before any port opens: a folder that cannot be used is the whole message
            prepare_folder(record)
        except OSError as exc:
            err.print(f"cannot record into {record}: {exc}", style="bold red", markup=False)
            raise typer.Exit(1) from None
        seconds, timeout = _recorded_run_limits(seconds, timeout, program)
    if program is not None and _AS_COMMAND:  # its detached children stay in sight
        from simmer.proctree import adopt_orphans  # (not when embedded: simmer.proctree)

        adopt_orphans()
    run_log = _RunLog() if program is not None else None
    if run_log is not None:
        out.print(f"the simulator's log goes to {run_log.path} (kept if it warns)", markup=False)
    free = {name: 0 for name, value in (("port_rx", port_rx), ("port_tx", port_tx)) if value == 0}
    options = RunOptions.for_config(
        sim.config,
        stream_port=STREAM_PORT if port is None else port,
        serial=serial,
        serial_link=serial_link,
        window=not headless,
        speed=pace,
        clock="lockstep" if lockstep else "realtime",
        link_delay=link_delay,
        seconds=seconds,
        program=program,
        answer=answer,
        timeout=timeout,
        record=record,
        record_limit=int(record_limit * 2**20),
        video=video,
    ).replace(**free)
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
    raise typer.Exit(served.exit_status)


def _run_config(
    config: Path | None, overrides: Mapping[str, object], **scenario: str | None
) -> SimConfig:
    """The run's configuration: the file, the command line's settings checked as the file's
    own are (two equal ports are refused before any port opens), then ``--start``,
    ``--block`` and ``--target``; a mistake is reported and ends the command."""
    from simmer.config import load_config, with_overrides

    given = {key: value for key, value in overrides.items() if value is not None}
    flags = " ".join(f"--{key.replace('_', '-')} {value}" for key, value in given.items())
    try:
        loaded = load_config(config)
        if given:
            loaded = with_overrides(loaded, given, f"{loaded.source} with {flags}")
    except ConfigError as exc:
        _report_config_error(exc)
        raise typer.Exit(1) from None
    return _with_scenario(loaded, **scenario)


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

        _report_config_error(ConfigError(loaded.source, probe_devices(loaded)))
        raise typer.Exit(1) from None
    _report_config_warnings(loaded)
    if loaded.origin:
        out.print(loaded.origin, markup=False)
    out.print(summarize(sim.config, seed=sim.seed, ports=False), markup=False)
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
        if served.ended_by == "program":
            ended = f"the program exited with status {served.program_status}"
        elif served.ended_by == "seconds":
            ended = f"the limit of {options.seconds} s of simulated time was reached"
        elif served.ended_by == "timeout":
            ended = (
                f"the {options.timeout} s wall-clock timeout was reached; the program was stopped"
            )
        else:
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
    """The simulator's log during a ``--program`` run, in a file of its own so that the
    program's printout is not mixed with it. The file is made by :func:`tempfile.mkstemp`:
    a name nobody can know beforehand, created only if nothing is there (the old
    ``simmer-PID.log`` followed a link planted at that name, and one was left per run). It
    is removed when the run ends unless it holds a warning or an error (:meth:`finish`)."""

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

    def _note(self, record: logging.LogRecord) -> bool:
        if record.levelno >= logging.WARNING:
            self.worth_keeping = True
        return True

    def finish(self) -> Path | None:
        """Close the file and give the log back to where it went before; the file if it is
        kept (it holds a warning or an error), else None (it is removed)."""
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
            "close it, or choose other ports with --port-rx, --port-tx and --port"
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


@app.command(
    cls=_Command,
    short_help="Convert a SimMeR config.py to the native TOML format.",
    epilog=_example("simmer convert config.py -o my_rover.toml"),
)
def convert(
    config: Annotated[
        Path, typer.Argument(help="A SimMeR config.py to convert.", metavar="CONFIG")
    ],
    output: Annotated[
        Path | None,
        typer.Option(
            "--output", "-o", help="TOML file to write (default: print it).", metavar="FILE"
        ),
    ] = None,
) -> None:
    """Convert a SimMeR config.py to the native TOML format, keeping its comments."""
    from simmer.config.convert import convert_simmer_py

    try:
        text = convert_simmer_py(config, output)
    except ConfigError as exc:
        _report_config_error(exc)
        raise typer.Exit(1) from None
    if output is None:
        out.print(text, markup=False, end="")
    else:
        out.print(
            Text.assemble(
                ("wrote", "bold green"), f" {output}; check it with `simmer check {output}`"
            )
        )


@app.command(
    "export-map",
    cls=_Command,
    short_help="Write the maze as JSON, as robot.maze() gives it.",
    epilog=_example("simmer export-map my_rover.toml -o maze.json"),
)
def export_map(
    config: ConfigArg = None,
    output: Annotated[
        Path, typer.Option("--output", "-o", help="JSON file to write.", metavar="FILE")
    ] = Path("maze.json"),
) -> None:
    """Write the maze as a program may know it (walls, sizes, wall segments, floor, zones, the
    configured start, every device's mount) as JSON: what robot.maze() answers, for a program
    that also runs on the real robot. docs/localization.md says what each key means."""
    from simmer.localize.files import write_map

    sim = _simulation(config)
    try:
        write_map(sim, output)
    except OSError as exc:
        err.print(f"cannot write {output}: {exc}", style="bold red", markup=False)
        raise typer.Exit(1) from None
    out.print(f"wrote {output}", markup=False)


@app.command(
    cls=_Command,
    short_help="Write a lookup table of noise-free readings at every pose.",
    epilog=_example("simmer table my_rover.toml --step 1 --headings 0:360:1 -o table.npz"),
)
def table(
    config: ConfigArg = None,
    output: Annotated[
        Path,
        typer.Option("--output", "-o", help="Table to write: .npz or .csv.", metavar="FILE"),
    ] = Path("table.npz"),
    step: Annotated[
        float, typer.Option(help="Inches between positions (x and y).", metavar="INCHES")
    ] = 1.0,
    headings: Annotated[
        str, typer.Option(help="Headings START:STOP:STEP in degrees.", metavar="RANGE")
    ] = "0:360:1",
    sensor: Annotated[
        list[str] | None,
        typer.Option(
            help="A sensor to include (repeat it; default: every one it can).", metavar="ID"
        ),
    ] = None,
) -> None:
    """Write the readings each sensor gives with its noise off at every position (every STEP
    inches, half a step from the walls' lines) and heading, from the walls alone (no block):
    ultrasonic, infrared and compass sensors, with the simulator's own geometry."""
    from rich.progress import Progress

    from simmer.localize.files import write_table
    from simmer.world.expected import parse_headings

    sim = _simulation(config)
    try:
        angles = parse_headings(headings)
        with Progress(console=err, transient=True) as progress:
            task = progress.add_task("casting rays", total=None)
            done = lambda row, rows: progress.update(task, completed=row, total=rows)  # noqa: E731
            count, ids = write_table(sim, output, step, angles, sensor, done)
    except (ValueError, OSError) as exc:
        err.print(f"cannot write the table: {exc}", style="bold red", markup=False)
        raise typer.Exit(1) from None
    out.print(f"wrote {output}: {count:,} readings of {', '.join(ids)}", markup=False)


def _simulation(config: Path | None) -> Simulation:
    """The simulation of a configuration, or its problems and exit status 1."""
    from simmer.world import Simulation

    try:
        return Simulation.from_config(config)
    except ConfigError as exc:
        _report_config_error(exc)
        raise typer.Exit(1) from None


@app.command(
    cls=_Command,
    short_help="Draw a recorded run: path.png and sensors.png.",
    epilog=_example("simmer plot runs/bias"),
)
def plot(folder: RunFolder) -> None:
    """Draw a recorded run into its folder: path.png (the path over the maze, commands
    numbered, collisions marked) and sensors.png (readings against time); report.md links
    them."""
    from simmer.errors import PlotError
    from simmer.record.plots import plot_run

    try:
        written = plot_run(folder, say=lambda line: out.print(line, markup=False))
    except PlotError as exc:
        err.print(str(exc), style="bold red", markup=False)
        raise typer.Exit(1) from None
    for path in written:
        out.print(f"wrote {path}", markup=False)


TrustOption = Annotated[
    bool,
    typer.Option(
        "--trust",
        help="Import the plug-ins the run was recorded with (their code runs): only for a "
        "folder from someone you trust. Without it, a run with plug-ins is not re-simulated.",
    ),
]
PluginOption = Annotated[
    list[Path] | None,
    typer.Option(
        "--plugin",
        help="Re-simulate with this plug-in file (your own copy) instead of the ones the run "
        "names; repeat for each.",
        show_default=False,
    ),
]
MaxSecondsOption = Annotated[
    float | None,
    typer.Option(
        "--max-seconds",
        help="Re-simulate at most this many simulated seconds (default: 3600); a folder whose "
        "events go further is refused.",
        callback=_number_check(
            "--max-seconds", "seconds", MAX_SIMULATED_SECONDS, "MAX_SIMULATED_SECONDS", zero=True
        ),
        show_default=False,
    ),
]


def _load_recording(
    folder: Path, trust: bool, plugins: list[Path] | None, max_seconds: float | None
) -> Recording:
    """Re-simulate a run folder, saying whether it matches its recording; exit status 1 with
    one line if it cannot be replayed."""
    from simmer.errors import ReplayError
    from simmer.record.runfolder import MAX_RUN_SECONDS
    from simmer.view.replay_model import Recording

    out.print(f"re-simulating the run in {folder} ...", markup=False)
    try:
        recording = Recording.load(
            folder,
            trust=trust,
            plugins=plugins or None,
            max_seconds=MAX_RUN_SECONDS if max_seconds is None else max_seconds,
        )
    except ReplayError as exc:
        err.print(str(exc), style="bold red", markup=False)
        raise typer.Exit(1) from None
    check = recording.check
    for i, line in enumerate(check.lines()):
        if check.matches and check.incomplete is None:
            out.print(line, markup=False)
        else:
            err.print(line, style="bold red" if i == 0 else "yellow", markup=False)
    return recording


@app.command(
    cls=_Command,
    short_help="Replay a recorded run in a window (or --check it).",
    epilog=_example("simmer replay runs/bias"),
)
def replay(
    folder: RunFolder,
    check: Annotated[
        bool,
        typer.Option(
            "--check",
            help="Only re-simulate and compare with the recording, without a window: exit "
            "status 1 if they differ.",
        ),
    ] = False,
    trust: TrustOption = False,
    plugin: PluginOption = None,
    max_seconds: MaxSecondsOption = None,
) -> None:
    """Replay a recorded run in a window: play, pause, speed, a timeline to drag, the commands
    beside the maze (H lists the keys). It is simulated again from the recorded configuration,
    seed and inputs, and says whether that matches the recording (and where it first differs
    if not)."""
    recording = _load_recording(folder, trust, plugin, max_seconds)
    if check:
        raise typer.Exit(0 if recording.check.matches else 1)
    from simmer.errors import SimmerError
    from simmer.ui.replay import run_replay

    try:
        run_replay(recording, echo=lambda line: out.print(line, markup=False))
    except SimmerError as exc:
        err.print(str(exc), style="bold red", markup=False)
        raise typer.Exit(1) from None


@app.command(
    cls=_Command,
    short_help="Cut a clip of a recorded run into a video (.mp4 or .gif).",
    epilog=_example("simmer render runs/manual --from 5 --to 20 -o manual_clip.mp4"),
)
def render(
    folder: RunFolder,
    output: Annotated[
        Path | None,
        typer.Option(
            "-o",
            "--output",
            help="The clip: .mp4 (H.264) or .gif (default: replay.mp4 in the run folder).",
            show_default=False,
            metavar="FILE",
        ),
    ] = None,
    start: Annotated[
        float | None,
        typer.Option(
            "--from",
            help="Start, in seconds from the start of the run (default: its start).",
            show_default=False,
            metavar="SECONDS",
        ),
    ] = None,
    end: Annotated[
        float | None,
        typer.Option(
            "--to",
            help="End, in seconds from the start of the run (default: its end).",
            show_default=False,
            metavar="SECONDS",
        ),
    ] = None,
    trust: TrustOption = False,
    plugin: PluginOption = None,
    max_seconds: MaxSecondsOption = None,
) -> None:
    """Cut a clip of a recorded run into a video: what the window shows (with the path driven
    so far), at 30 frames per simulated second, drawn without a display."""
    from simmer.errors import ReplayError
    from simmer.ui.clip import write_clip

    recording = _load_recording(folder, trust, plugin, max_seconds)
    path = output if output is not None else folder / "replay.mp4"
    try:
        frames = write_clip(recording, path, start, end, run_folder=output is None)
    except ReplayError as exc:
        err.print(str(exc), style="bold red", markup=False)
        raise typer.Exit(1) from None
    seconds = frames / recording.timeline.fps
    out.print(f"wrote {path} ({frames} frames, {seconds:.2f} s)", markup=False)


class Engine(StrEnum):
    """Choices of ``simmer sweep --engine``."""

    local = "local"
    dask = "dask"


@app.command(
    cls=_Command,
    short_help="Run a program over seeds and settings: success rates.",
    epilog=_example("simmer sweep sweep_dead_reckoning.toml --workers 2"),
)
def sweep(
    sweep_file: Annotated[Path, typer.Argument(help="Sweep file (.toml).", metavar="SWEEP")],
    output: Annotated[
        Path | None,
        typer.Option(
            "-o",
            "--output",
            help="Folder for results.csv and summary.md (default: SWEEP-results in the current "
            "folder, SWEEP being the sweep file's name without .toml).",
            show_default=False,
            metavar="DIR",
        ),
    ] = None,
    workers: Annotated[
        int | None,
        typer.Option(
            help="Worker processes (default: one per core).",
            callback=_number_check(
                "--workers", "workers", MAX_WORKERS, "MAX_WORKERS", zero=True, low=1
            ),
            show_default=False,
            metavar="N",
        ),
    ] = None,
    resume: Annotated[
        bool,
        typer.Option("--resume", help="Keep the runs already in results.csv; run only the others."),
    ] = False,
    engine: Annotated[
        Engine,
        typer.Option(help="Where runs go: local processes or Dask.", metavar="local|dask"),
    ] = Engine.local,
    address: Annotated[
        str | None,
        typer.Option(
            help="Dask scheduler (tcp://host:8786); none: a local Dask cluster.",
            metavar="ADDRESS",
        ),
    ] = None,
) -> None:
    """Run a controller over seeds and settings in parallel: results.csv (a row per run) and
    summary.md (success rate per setting with 95% intervals)."""
    from simmer.errors import SweepError, UnsafeOutput
    from simmer.sweep import dask_engine, load_sweep, local_pool, run_sweep

    try:
        spec = load_sweep(sweep_file)
        chosen = dask_engine(address, workers) if engine is Engine.dask else local_pool(workers)
    except (SweepError, RuntimeError) as exc:
        err.print(str(exc), style="bold red", markup=False)
        raise typer.Exit(1) from None
    folder = output or Path(f"{sweep_file.stem}-results")  # the student's folder, not the file's
    try:
        done = run_sweep(
            spec,
            folder,
            engine=chosen,
            workers=workers,
            resume=resume,
            console=err,
            source=sweep_file.name,
        )
    except SweepError as exc:  # a setting no run could use: found before any run
        err.print(f"{sweep_file}: {exc}", style="bold red", markup=False)
        raise typer.Exit(1) from None
    except (FileExistsError, ValueError, UnsafeOutput) as exc:  # a link where it writes
        err.print(str(exc), style="bold red", markup=False)
        raise typer.Exit(1) from None
    except KeyboardInterrupt as exc:
        import signal

        signum = getattr(exc, "signum", signal.SIGINT)
        err.print(
            f"stopped ({signal.Signals(signum).name}); the workers and their programs are "
            f"stopped; finished runs are in {folder / 'results.csv'} (--resume goes on)",
            markup=False,
        )
        raise typer.Exit(128 + signum) from None
    out.print(
        f"{done.successes}/{done.runs} succeeded ({done.ran} run now, {done.wall_time:.1f} s); "
        f"wrote {folder / 'results.csv'} and {folder / 'summary.md'}",
        markup=False,
    )


@app.command(
    cls=_Command,
    short_help="Type commands (u0, w0-6) and see the replies.",
    epilog=_example("simmer console          (then type u0,u1,u2,u3 or w0-6; help lists them)"),
)
def console(
    host: Annotated[str, typer.Option(help="Simulator address.", metavar="ADDRESS")] = (
        "127.0.0.1"
    ),
    port: Annotated[
        int, typer.Option(help="Persistent protocol port.", metavar="PORT")
    ] = STREAM_PORT,
    two_port: Annotated[
        bool,
        typer.Option("--two-port", help="Use SimMeR's two-port scheme (61200/61201) instead."),
    ] = False,
    serial: Annotated[
        str | None,
        typer.Option(
            help="Talk to a serial port (virtual or the robot's) instead.", metavar="PORT"
        ),
    ] = None,
    baud: Annotated[int, typer.Option(help="Serial baud rate.", metavar="BAUD")] = 9600,
    framed: Annotated[
        bool,
        typer.Option(
            "--framed",
            help="Speak SimMeR v1.2's framed text ([u0] -> [u0:15.45]) over the two-port "
            "scheme or --serial, as a simulator with protocol = 'framed' (a v1.2 config.py) does.",
        ),
    ] = False,
) -> None:
    """Interactive console: type commands (u0, w0-6, ...) and see the replies."""
    from simmer.client import connect
    from simmer.console import run_console
    from simmer.errors import ClientError

    try:
        client = connect(
            host,
            port,
            scheme="two-port" if two_port else None,
            serial=serial,
            baudrate=baud,
            framed=framed,
        )
    except ClientError as exc:
        err.print(str(exc), style="bold red")
        raise typer.Exit(1) from None
    with client:
        run_console(client)


def main() -> None:
    """Entry point of the ``simmer`` console script."""
    logging.basicConfig(level=logging.INFO, format="%(levelname)s %(name)s: %(message)s")
    _AS_COMMAND.append(True)
    app()
