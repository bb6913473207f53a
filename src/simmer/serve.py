"""``simmer run``: serve every transport and run the loop, with the window or headless.

Kept out of :mod:`simmer.cli` so the window, the headless run and the tests share one path.
"""

from __future__ import annotations

import logging
import signal
import subprocess
import sys
import threading
from collections.abc import Callable
from dataclasses import dataclass
from types import FrameType
from typing import TYPE_CHECKING

from simmer.devices.lidar import Lidar
from simmer.ending import RunEnd
from simmer.lockstep import (
    EXIT_SECONDS,
    EXIT_TIMEOUT,
    NOT_PYTHON,
    Program,
    program_environment,
    runs_python,
    which_program,
)
from simmer.lockstep.output import ENCODING, ProgramOutput
from simmer.options import RunOptions
from simmer.proctree import descendants, stop_strays
from simmer.record import RunRecorder
from simmer.runner import Runner
from simmer.transport import Transports
from simmer.transport.link import Link, LinkModel
from simmer.transport.rplidar_pty import RPLidarServer
from simmer.world import Simulation
from simmer.world.events import Event, Observer, RunEvent, StepEvent
from simmer.world.outcome import Outcome

if TYPE_CHECKING:
    from simmer.config import SimConfig
    from simmer.transport.bus import CommandBus
    from simmer.ui.video import VideoRecorder

log = logging.getLogger("simmer.serve")


STOP_SIGNALS = ("SIGTERM", "SIGHUP")
"""Signals that stop a run as Ctrl-C does (``kill``, closing the terminal), where they exist."""


class RunStop(threading.Event):
    """The event that stops a run, which a signal handler can also set: without a lock
    (:meth:`set_from_signal`), as the main thread may be inside :meth:`set` itself when
    the signal lands (the window stops its run so). Once so set, :meth:`is_set` is True;
    :meth:`wait` does not see it (nothing waits on a run's stop: its loops poll it)."""

    def __init__(self) -> None:
        super().__init__()
        self._signalled = False

    def set_from_signal(self) -> None:
        """Set it from a signal handler (one plain assignment: no lock taken)."""
        self._signalled = True

    def is_set(self) -> bool:
        """Whether the run is to stop."""
        return self._signalled or super().is_set()


def _stop_on_signals(
    stop: RunStop, wake: Callable[[], None], received: list[str]
) -> Callable[[], None]:
    """Make :data:`STOP_SIGNALS` and Ctrl-C (SIGINT, unless it is ignored or another handler
    has it) stop a run as Esc does: note the signal in ``received``, set ``stop`` and
    ``wake`` the loop, so the run ends between two steps through its usual cleanup (serial
    link removed, ports closed, program stopped, recording finished). The handler raises
    nothing and takes no lock. An exception raised wherever the main thread happens to be
    can land inside the simulation's step or a recording's write: Ctrl-C raised
    KeyboardInterrupt, which landing right after a trace write had those rows written again
    at the close (trace.csv ran backwards; about once in 48 Ctrl-Cs to recorded runs, with
    a missing report or a replay that differed). It can also be swallowed (a signal landing
    in a finalizer, which Python ignores exceptions from, once left a run that never
    stopped) or leave a lock held, which the interrupted code never releases. Returns what
    puts the previous handlers back: :func:`serve` does so only once the recording is
    finished (Ctrl-C landing in its close, the default handler back, left no report). Off
    the main thread (tests) nothing changes: only the main thread may install handlers."""
    if threading.current_thread() is not threading.main_thread():
        return lambda: None

    def handle(signum: int, _frame: FrameType | None) -> None:
        received.append(signal.Signals(signum).name)
        stop.set_from_signal()
        wake()

    previous = {}
    for name in STOP_SIGNALS:
        if (number := getattr(signal, name, None)) is not None:
            previous[number] = signal.signal(number, handle)
    if signal.getsignal(signal.SIGINT) is signal.default_int_handler:  # not ignored
        previous[signal.SIGINT] = signal.signal(signal.SIGINT, handle)

    def restore() -> None:
        for number, handler in previous.items():
            signal.signal(number, handler)

    return restore


class _Said:
    """Where the run's own lines go: said at once, except while a program's printout passes
    through (:meth:`hold`, from just before it starts until its pipes are drained): then they
    are kept, and said in order by :meth:`release`, so no line of the program's is split by
    one of SimMeR's, and what is said after the program does not depend on when it wrote."""

    def __init__(self, echo: Callable[[str], None]) -> None:
        self._echo = echo
        self._held: list[str] | None = None

    def __call__(self, line: str) -> None:
        if self._held is None:
            self._echo(line)
        else:
            self._held.append(line)

    def hold(self) -> None:
        """Keep the lines said from now on."""
        self._held = []

    def release(self) -> None:
        """Say the lines kept, and say lines at once again."""
        held, self._held = self._held or [], None
        for line in held:
            self._echo(line)


@dataclass
class Served:
    """How a run served by :func:`serve` went."""

    runner: Runner
    outcome: Outcome
    ended_by: RunEnd
    """``quit`` (Esc, closing the window, Ctrl-C, a signal), ``seconds`` (the simulated-time
    limit), ``program`` (the control program exited) or ``timeout`` (the wall-clock limit)."""
    program_status: int | None = None
    """The control program's exit status, if it ended the run."""
    program_started: bool = False
    recording_stopped: str | None = None
    """Why the recording stopped before the run ended (a full disk, its size limit), if it did."""

    @property
    def exit_status(self) -> int:
        """What ``simmer run`` exits with: the program's own status when it ended the run,
        :data:`~simmer.lockstep.EXIT_TIMEOUT` or (with a program) :data:`~simmer.lockstep.
        EXIT_SECONDS` when a limit did, 0 otherwise."""
        if self.ended_by is RunEnd.PROGRAM:
            return self.program_status or 0
        if self.ended_by is RunEnd.TIMEOUT:
            return EXIT_TIMEOUT
        if self.ended_by is RunEnd.SECONDS and self.program_started:
            return EXIT_SECONDS
        return 0


def make_link(sim: Simulation, runner: Runner) -> Link | None:
    """The run's link model, if its configuration turns one on (``[link]``): its draws from
    the run's seed, its times on the runner's clock (in real time a reply is held back until
    the simulation reaches its arrival), what it did in the run's events."""
    params = sim.config.settings.link.resolved()
    if params is None:
        return None
    clock = runner.clock

    def hold(seconds: float, deliver: Callable[[], None]) -> None:
        if clock.answers_at_once and seconds > 0:  # real time: until the simulation is there
            clock.at(sim.time + seconds, deliver)
        else:  # lockstep: the program's clock has moved past the arrival already
            deliver()

    def emit(what: str, value: float, detail: str) -> None:
        if sim.observers:
            sim.emit(RunEvent(sim.time, what, value, sim.steps, detail))

    return Link(LinkModel(params, sim.stream), clock, hold, emit)


def serve(sim: Simulation, options: RunOptions, echo: Callable[[str], None] = print) -> Served:
    """Serve every transport and run ``sim`` until the user quits (Esc, closing the window,
    Ctrl-C, SIGTERM, SIGHUP), ``seconds`` of simulated time pass, the ``program`` (a control
    program's command line, started here on this run's ports) exits, or ``timeout`` wall
    seconds pass; with a window or headless, in real time or in lockstep, all as ``options``
    say (:class:`~simmer.options.RunOptions`); what it does is said through ``echo``. With
    ``record`` (a folder), the run is recorded there (:class:`~simmer.record.RunRecorder`) until it
    ends, however it ends. With ``video`` (an .mp4 or .gif file), what the window shows is
    recorded there at 30 frames per simulated second (:class:`~simmer.ui.video.VideoRecorder`),
    with a window or headless, and the file is finished however the run ends. A recording
    that reaches ``record_limit`` bytes or fills the disk stops (the run goes on), and
    :attr:`Served.recording_stopped` says so. When the run ends, every process the program
    started is stopped, however it detached (:mod:`simmer.proctree`). With ``answer``, the
    program's standard input is that text, a line, then its end (what a student types at
    the program's ``input()`` prompt: the project's target zone). Unless ``program_output``
    says where, the program's output and error pass through this process's own
    (:mod:`simmer.lockstep.output`), and what is said through ``echo`` from the program's start
    until its last output is shown is said after it, each line whole.

    Raises ``OSError`` if a port cannot be opened, the program cannot be started or the
    ``record`` folder cannot be written (FileExistsError if it holds a run already), and
    :class:`~simmer.errors.SimmerError` if no window can be opened or something is already at
    ``serial_link``.
    """
    link_on = sim.config.settings.link.on
    delay = 0.0 if link_on and options.link_delay is None else options.link_delay
    runner = Runner(sim, speed=options.speed, lockstep=options.lockstep, link_delay=delay)
    outcome = Outcome.attach(sim)
    outcome.over_limit_count = lambda: runner.over_limit
    link_model = make_link(sim, runner)
    if link_model is not None:
        outcome.link_counts = link_model.model.counts.as_dict
    stop = RunStop()
    ended: list[RunEnd] = []  # who stopped the run first
    said = _Said(echo)
    started: Program | None = None
    printouts: list[ProgramOutput] = []  # the program's, passing through
    # This process's descendants before the program started: what is not among them at
    # the end is the program's, even if Ctrl-C landed before ``started`` held it.
    before: set[int] | None = None
    signalled: list[str] = []
    recorder: RunRecorder | None = None
    filming: VideoRecorder | None = None
    restore_signals = _stop_on_signals(stop, runner.bus.wake_from_signal, signalled)
    try:  # until the recording is finished, a signal only sets the stop
        try:
            transports = Transports(
                runner.bus, sim.config, options, clock=runner.clock, link_model=link_model
            )
            with transports:
                if transports.lidar is not None:
                    sim.add_observer(_feed_lidar(sim, transports.lidar))
                if options.record is not None:
                    used = options.replace(
                        link_delay=runner.link_delay if options.lockstep else None
                    )
                    recorder = RunRecorder(sim, options.record, used, outcome, on_stop=_say(said))
                    said(f"recording the run into {options.record}")
                if options.video is not None:
                    from simmer.ui.video import VideoRecorder

                    filming = VideoRecorder(
                        sim, options.video, controls=runner, window=options.window
                    )
                    said(f"recording a video into {options.video}")
                for line in transports.describe():
                    said(line)
                if options.lockstep:
                    said(
                        f"lockstep clock: simulated time advances only when the program sleeps, "
                        f"and {runner.link_delay:g} s per message"
                    )
                    if options.program is not None and not runs_python(options.program):
                        said(NOT_PYTHON.format(command=options.program))
                if not options.window:
                    pace = (
                        "as fast as possible"
                        if options.speed is None
                        else f"{options.speed:g}x real time"
                    )
                    said(f"running headless, {pace}; Ctrl-C to stop")
                if options.program is not None:
                    said(f"starting the program: {which_program(options.program)}")
                    said.hold()  # the program's printout only, until it is over
                    before = descendants()
                    started = _start_program(
                        options, transports, sim.config, runner.bus, stop, ended, printouts
                    )
                    sim.emit(RunEvent(sim.time, "program-start", 0.0, sim.steps, options.program))
                if options.window:
                    from simmer.ui import run_window

                    shown = said if options.program is None else None  # not after the program
                    run_window(runner, until=options.seconds, stop=stop, echo=shown)
                else:
                    runner.run(stop_event=stop, until=options.seconds)
                if signalled:
                    said(f"stopped ({signalled[0]})")
                    ended.insert(0, RunEnd.QUIT)
                elif not ended:
                    limit = options.seconds is not None and sim.time >= options.seconds - 1e-9
                    ended.append(RunEnd.SECONDS if limit else RunEnd.QUIT)
        except KeyboardInterrupt:
            said("stopped")
            ended.append(RunEnd.QUIT)
        except BaseException:
            ended.append(RunEnd.ERROR)
            if recorder is not None:  # keep what was recorded, with a report
                recorder.close(RunEnd.ERROR)
            raise
        finally:
            runner.bus.close()
            if started is not None:
                started.stop()
            if before is not None:
                stop_strays(before)
            for printout in printouts:  # all of it shown, its last line ended
                printout.finish()
            said.release()
            if filming is not None:
                _finish_video(filming, said)
        status = (
            started.process.returncode
            if started is not None and ended[0] is RunEnd.PROGRAM
            else None
        )
        if status is not None:  # here, in the thread that owns the simulation
            sim.emit(RunEvent(sim.time, "program-exit", float(status), sim.steps))
        served = Served(runner, outcome, ended[0], status, program_started=started is not None)
        if recorder is not None:
            recorder.close(served.ended_by, status)
            served.recording_stopped = recorder.stopped
    finally:
        restore_signals()
    return served


def _feed_lidar(sim: Simulation, server: RPLidarServer) -> Observer:
    """An observer giving the virtual RPLidar each new scan of its LiDAR after a step, in the
    loop thread that owns the simulation (it reads the scan; it commands nothing)."""

    def feed(event: Event) -> None:
        if isinstance(event, StepEvent):
            device = sim.robot.devices.get(server.device)
            if isinstance(device, Lidar):
                server.scan(device.number, device.directions, device.distances)

    return feed


def _say(echo: Callable[[str], None]) -> Callable[[str], None]:
    """Say a recording stopped, in the log and where the run's messages go."""

    def say(line: str) -> None:
        log.error("%s; the run goes on", line)
        echo(f"{line}; the run goes on")

    return say


def _finish_video(filming: VideoRecorder, echo: Callable[[str], None]) -> None:
    """Finish the video file and say how long it is, or why it could not be written."""
    try:
        filming.close()
    except Exception as exc:  # the run itself went well: say so, and keep its outcome
        log.error("the video %s could not be written: %s", filming.path, exc)
        echo(f"the video {filming.path} could not be written: {exc}")
    else:
        echo(f"video: {filming.path} ({filming.frames} frames, {filming.seconds:.2f} s)")


def _start_program(
    options: RunOptions,
    transports: Transports,
    config: SimConfig,
    bus: CommandBus,
    stop: threading.Event,
    ended: list[RunEnd],
    printouts: list[ProgramOutput],
) -> Program:
    """Start the control program of ``options`` on this run's ports; a thread ends the run
    when it exits or at the wall-clock ``timeout`` (then stopping its whole process tree).
    Unless ``options`` give it an output of its own (a sweep's), its standard output and
    error are pipes, copied to this process's from the start (added to ``printouts``, so
    that the run drains them however it ends)."""
    ports = {
        "port_rx": transports.two_port.port_rx,
        "port_tx": transports.two_port.port_tx,
        "stream": transports.stream.port,
    }
    settings = config.settings
    configured = {"port_rx": settings.port_rx, "port_tx": settings.port_tx}
    env = program_environment(ports, transports.host, configured=configured)
    if transports.serial is not None:
        env["SIMMER_SERIAL"] = str(transports.serial.link or transports.serial.path)
    if transports.lidar is not None:
        env["SIMMER_LIDAR_SERIAL"] = transports.lidar.path
    assert options.program is not None
    command, timeout = options.program, options.timeout
    output = options.program_output
    if output is None and sys.stdout is not None and sys.stderr is not None:
        output = subprocess.PIPE  # one pipe each for its output and its error
        env.setdefault("PYTHONIOENCODING", ENCODING)
        sys.stdout.flush()  # what SimMeR said so far goes first
        sys.stderr.flush()
    program = Program.start(
        command,
        env,
        options.answer,
        folder=options.program_folder,
        output=output,
        box=options.box,
        ports=list(ports.values()),
    )
    if program.process.stdout is not None and sys.stdout is not None and sys.stderr is not None:
        printouts.append(ProgramOutput(program.process, sys.stdout, sys.stderr))

    def watch() -> None:
        status = program.wait(timeout)
        if status is None:
            ended.append(RunEnd.TIMEOUT)
            program.stop()
        else:
            ended.append(RunEnd.PROGRAM)
        stop.set()
        bus.interrupt()  # the loop may be waiting for a message that will not come

    threading.Thread(target=watch, name="simmer-program", daemon=True).start()
    return program
