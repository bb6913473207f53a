"""Every exception SimMeR raises on purpose, in one small tree (a test keeps them all here).

Catch :class:`SimmerError` to catch the errors. Each carries a message written for a
student: what is wrong, where, and what to do about it. The four signals at the bottom are
not errors: they stop a run or a check from inside and keep the base Python gives their
meaning (a limit is an ``Exception`` a policy may see; Ctrl-C a ``KeyboardInterrupt``)::

    SimmerError
    ├── ConfigError            a configuration could not be loaded (every issue)
    ├── WrongThread            a simulation driven from another thread
    ├── DeviceKindError        a device kind registered twice, unknown or not honouring it
    ├── CommandError           a command could not be carried out
    ├── ClientError            raised by simmer.client
    │   ├── ConnectionFailed
    │   └── ReplyTimeout
    ├── ReplayError            a run folder cannot be replayed or rendered
    │   └── UntrustedRun       its configuration names code (plug-ins, device files)
    ├── PlotError              a run folder cannot be plotted
    ├── UnsafeOutput + OSError a file's name holds a link or no regular file: not written
    ├── ProgramNotFound + FileNotFoundError  ``--program``'s first word is not on PATH
    ├── BusClosed              the simulation loop has stopped
    ├── SweepError + ValueError     a sweep file SimMeR cannot run
    ├── ScenarioError + ValueError  a scenario setting that cannot be met
    ├── RunFolderError + ValueError a run folder's events or trace cannot be read
    ├── FolderExists + ValueError   ``simmer new`` would write over files
    ├── GenerateError + ValueError  no generated maze met the asked ranges
    ├── FlagError + ValueError      a command-line flag ``simmer run`` refuses
    ├── BatchError + ValueError     a batch or an environment given what it cannot take
    ├── PortsError + ValueError     ``--ports`` or ``SIMMER_PORTS`` names no three ports
    ├── TapError               ``simmer tap`` cannot open the robot's port or its folder
    ├── RoutineError + ValueError   a robot the calibration routine cannot run on
    └── CalibrationError + ValueError  a run folder that is not the routine's run

    LimitReached (Exception)       a policy ran into its run's limit
    └── WallLimitReached           the wall-clock limit, raised in the policy's thread
    SweepStopped (KeyboardInterrupt)  a signal stopped the sweep
    ExitCalled (SystemExit)           ``os._exit`` called while ``simmer check`` runs a plug-in

The ``ValueError`` second base is kept for the code that raised them as value errors (a
sweep setting, a scenario cell, a recording read back and a destination folder are values the
user gave).
"""

from __future__ import annotations

import signal
import sysconfig
import traceback
from collections.abc import Sequence
from dataclasses import dataclass
from functools import cache
from pathlib import Path

__all__ = [
    "BatchError",
    "BusClosed",
    "ClientError",
    "CommandError",
    "ConfigError",
    "ConfigIssue",
    "ConnectionFailed",
    "DeviceKindError",
    "ExitCalled",
    "FolderExists",
    "GenerateError",
    "LimitReached",
    "PlotError",
    "ProgramNotFound",
    "ReplayError",
    "ReplyTimeout",
    "ScenarioError",
    "SimmerError",
    "SweepError",
    "SweepStopped",
    "UnsafeOutput",
    "UntrustedRun",
    "WallLimitReached",
    "WrongThread",
]


class SimmerError(Exception):
    """Base class of every error SimMeR raises deliberately."""


@dataclass(frozen=True)
class ConfigIssue:
    """One problem found in a configuration: the key path, what is wrong and (maybe) a line."""

    key: str
    message: str
    line: int | None = None

    def render(self, source: str) -> str:
        """Format as ``file[:line]: key: message``, the shape editors and students can follow."""
        where = f"{source}:{self.line}" if self.line is not None else source
        return f"{where}: {self.key}: {self.message}" if self.key else f"{where}: {self.message}"


class ConfigError(SimmerError):
    """A configuration could not be loaded; holds every issue found, not just the first."""

    def __init__(self, source: str | Path, issues: list[ConfigIssue]) -> None:
        self.source = str(source)
        self.issues = list(issues)
        super().__init__(self.render())

    def render(self) -> str:
        """All issues, one per line."""
        return "\n".join(issue.render(self.source) for issue in self.issues)


class WrongThread(SimmerError):
    """A simulation was driven from a thread other than the one running its loop (transports
    and windows hand their commands to the loop instead)."""


class DeviceKindError(SimmerError):
    """A device kind is registered twice, unknown, or does not honour the device interface."""


class CommandError(SimmerError):
    """A command could not be carried out (the reply to it is NaN)."""


class ClientError(SimmerError):
    """Base class of errors raised by :mod:`simmer.client`."""


class ConnectionFailed(ClientError):
    """The simulator (or robot) could not be reached."""


class ReplyTimeout(ClientError):
    """No complete reply arrived in time."""


class ReplayError(SimmerError):
    """A run folder cannot be replayed or rendered (not a run folder, unreadable files, a
    configuration that no longer loads, a time outside the run)."""


class UntrustedRun(ReplayError):
    """A run folder's configuration names code (plug-ins, a device class's file, a kind only
    a plug-in or package defines), and re-simulating it would run that code."""

    def __init__(self, code: Sequence[str], where: str = "", *, plugins: bool = False) -> None:
        self.code = list(code)
        self.names_plugins = plugins
        own_copies = (
            "; or name your own copies of its plug-ins with --plugin FILE" if plugins else ""
        )
        super().__init__(
            f"{where or 'the manifest'}: the run's configuration names code: "
            f"{'; '.join(self.code)}. Re-simulating it runs that code, and a run folder is data, "
            "so SimMeR does not unless asked: if you trust whoever made the folder, add "
            f"--trust{own_copies}"
        )


class PlotError(SimmerError):
    """A run folder could not be plotted (no trace, no manifest, unreadable files)."""


class UnsafeOutput(SimmerError, OSError):
    """A file SimMeR would write (into a run folder, most often) is at a name that holds a
    symbolic link, a folder, a pipe or a device, or the folder is a link: nothing is written
    (an ``OSError``, so that "cannot write" handlers say it)."""


class ProgramNotFound(SimmerError, FileNotFoundError):
    """The first word of ``--program`` (``python``) names no file on the run's ``PATH``: the
    program runs in the student's environment, and this terminal does not have it."""


class BusClosed(SimmerError):
    """The simulation loop has stopped; no more messages will be answered."""


class BatchError(SimmerError, ValueError):
    """A batch (:mod:`simmer.batch`) or a Gymnasium environment (:mod:`simmer.gym`) given a
    configuration, seeds, a command or an option it cannot take: one plain line."""


class SweepError(SimmerError, ValueError):
    """The sweep file is not a sweep SimMeR can run (the message says why)."""


class ScenarioError(SimmerError, ValueError):
    """A scenario setting that cannot be met: a bad cell, zone name or place, by its key."""

    def __init__(self, key: str, message: str) -> None:
        super().__init__(f"{key}: {message}")
        self.key = key
        self.message = message


class RunFolderError(SimmerError, ValueError):
    """A run folder's ``events.jsonl`` or ``trace.csv`` cannot be read: unreadable, larger than
    a recording holds, or not what SimMeR writes (the message names the file and, for an event,
    its line). Raised only by :mod:`simmer.record.reader`; a plot or a replay says it as its
    own :class:`PlotError` or :class:`ReplayError`."""


class FolderExists(SimmerError, ValueError):
    """The destination holds files already: nothing is written over them."""


class GenerateError(SimmerError, ValueError):
    """No maze met the generator's asked ranges within ``MAX_ATTEMPTS`` draws of its seed (the
    message says which range to widen)."""


class PortsError(SimmerError, ValueError):
    """A ``--ports`` flag or ``SIMMER_PORTS`` value that names no three ports; its message is
    the one line to print (what was given, where, and what to write instead)."""


class TapError(SimmerError):
    """``simmer tap`` cannot start: the robot's port will not open, or the run folder cannot
    be written (one line naming it)."""


class RoutineError(SimmerError, ValueError):
    """The configuration's robot cannot run the calibration routine (no ultrasonic sensor, no
    drive that goes straight, no room ahead of its start), or the command was given too little
    to write or fit it."""


class CalibrationError(SimmerError, ValueError):
    """A tap's run folder does not hold the calibration routine's run."""


class FlagError(SimmerError, ValueError):
    """A command-line flag's value refused, with the flag (``--speed``; None when the message
    names the flags itself)."""

    def __init__(self, message: str, flag: str | None = None) -> None:
        super().__init__(f"{flag}: {message}" if flag else message)
        self.flag = flag
        self.message = message


# ----------------------------------------------------------------------------- not errors


class LimitReached(Exception):
    """A policy ran into one of the run's limits: ``status`` is how the run ended (``seconds``
    or ``timeout``, a :class:`~simmer.ending.RunEnd`'s value)."""

    def __init__(self, status: str) -> None:
        super().__init__(status)
        self.status = status


class WallLimitReached(LimitReached):
    """The wall-clock limit, raised in a thread from outside (so it takes no arguments)."""

    def __init__(self) -> None:
        super().__init__("timeout")


class SweepStopped(KeyboardInterrupt):
    """A signal stopped the sweep (as Ctrl-C does); ``signum`` and ``name`` say which."""

    def __init__(self, signum: int) -> None:
        self.signum = signum
        self.name = signal.Signals(signum).name
        super().__init__(self.name)


class ExitCalled(SystemExit):
    """``os._exit`` called by a plug-in or a device while ``simmer check`` runs it."""


# ----------------------------------------------------------------------------- user code

SIMMER_DIR = Path(__file__).resolve().parent
"""simmer's own package: its frames are never the place to fix a student's device."""


@cache
def _library_dirs() -> tuple[Path, ...]:
    """The standard library and installed packages (looked up once, when first needed)."""
    paths = sysconfig.get_paths()
    keys = ("stdlib", "platstdlib", "purelib", "platlib")
    return tuple({Path(paths[key]).resolve() for key in keys if key in paths})


def user_frame(exc: BaseException) -> traceback.FrameSummary | None:
    """The innermost frame of ``exc``'s traceback in the user's own code, if any.

    Frames in simmer's package are never the user's; frames in the standard library or
    installed packages only when nothing else outside simmer is on the traceback (a plug-in
    installed as a package).
    """
    outside: list[traceback.FrameSummary] = []
    for frame in traceback.extract_tb(exc.__traceback__):
        if frame.filename.startswith("<"):
            continue  # <string>, <frozen ...>: no file to open
        path = Path(frame.filename).resolve()
        if not path.is_relative_to(SIMMER_DIR):
            outside.append(frame)
    for frame in reversed(outside):
        path = Path(frame.filename).resolve()
        if not any(path.is_relative_to(lib) for lib in _library_dirs()):
            return frame
    return outside[-1] if outside else None


def describe_exception(exc: BaseException, base: Path | None = None) -> str:
    """``Type: message (file.py line N)`` naming :func:`user_frame`; the file is shown relative
    to ``base`` when it lies under it, else by name."""
    if isinstance(exc, SyntaxError) and exc.filename and not exc.filename.startswith("<"):
        where: tuple[str, int | None] | None = (exc.filename, exc.lineno)
        text = f"SyntaxError: {exc.msg}"
    else:
        frame = user_frame(exc)
        where = (frame.filename, frame.lineno) if frame is not None else None
        text = f"{type(exc).__name__}: {exc}" if str(exc) else type(exc).__name__
    if where is None:
        return text
    path = Path(where[0]).resolve()
    shown = path.name
    if base is not None and path.is_relative_to(base.resolve()):
        shown = path.relative_to(base.resolve()).as_posix()
    return f"{text} ({shown} line {where[1]})"
