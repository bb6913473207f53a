"""Every exception SimMeR raises on purpose, in one small tree.

Catch :class:`SimmerError` to catch them all. Each carries a message written for a
student: what is wrong, where, and what to do about it.
"""

from __future__ import annotations

from dataclasses import dataclass
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
