"""Every exception SimMeR raises on purpose, in one small tree.

Catch :class:`SimmerError` to catch them all. Each carries a message written for a
student: what is wrong, where, and what to do about it.
"""

from __future__ import annotations

import sysconfig
import traceback
from dataclasses import dataclass
from functools import cache
from pathlib import Path


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
