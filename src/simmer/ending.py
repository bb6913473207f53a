"""How a run ended (:class:`RunEnd`): one vocabulary for ``simmer run``, a recording and a sweep.

A served run's end is written to its folder's ``report.json`` (``ended_by``) and said in words
in ``report.md``; a sweep's run's end is results.csv's ``status`` and a few words in
``summary.md``. Both files keep the spellings they always had: each member is the string it is
written as, and where two spellings differ (a controller that finished is ``program`` in a
report and ``ok`` or ``error`` in a sweep's results) a method here says which, not a table
elsewhere.
"""

from __future__ import annotations

from contextlib import suppress
from enum import StrEnum

__all__ = ["RunEnd"]


class RunEnd(StrEnum):
    """How a run ended: a ``str`` (``RunEnd.SECONDS == "seconds"``), written as it is to
    ``report.json``'s ``ended_by`` and results.csv's ``status``; :attr:`words` says it in
    report.md, :attr:`label` in a sweep's summary.md."""

    QUIT = "quit"
    """Stopped by hand (Esc, closing the window, Ctrl-C or a signal): ``simmer run``."""
    SECONDS = "seconds"
    """The simulated-time limit (``--seconds``, a sweep's ``seconds``) ended it."""
    PROGRAM = "program"
    """The control program exited (a report; its exit status is beside it)."""
    TIMEOUT = "timeout"
    """The wall-clock limit (``--timeout``, a sweep's ``wall_seconds``) ended it."""
    ERROR = "error"
    """An error stopped it; in a sweep, the controller failed (non-zero exit status or an
    exception)."""
    CLOSED = "closed"
    """The recording was closed (a run recorded from Python)."""
    OK = "ok"
    """A sweep's run whose controller finished (exit status 0, or the policy returned)."""
    INVALID = "invalid"
    """A sweep's run whose overridden configuration does not validate."""
    CRASHED = "crashed"
    """A sweep's run whose worker process died."""
    STOPPED = "stopped"
    """A sweep's run that never began: the sweep was stopped first (never recorded)."""

    @property
    def words(self) -> str:
        """How report.md says it (its row "How it ended")."""
        match self:
            case RunEnd.QUIT:
                return "stopped by hand (Esc, closing the window, Ctrl-C or a signal)"
            case RunEnd.SECONDS:
                return "the --seconds limit of simulated time was reached"
            case RunEnd.PROGRAM:
                return "the control program exited"
            case RunEnd.TIMEOUT:
                return "the --timeout wall-clock limit was reached; the program was stopped"
            case RunEnd.ERROR:
                return "an error stopped it"
            case RunEnd.CLOSED:
                return "the recording was closed"
            case _:  # a sweep's status: never in a report SimMeR writes
                return self.value

    @property
    def label(self) -> str:
        """How a sweep's summary.md says it, before the time it ended at."""
        match self:
            case RunEnd.OK:
                return "finished"
            case RunEnd.ERROR:
                return "failed"
            case RunEnd.SECONDS:
                return "simulated-time limit"
            case RunEnd.TIMEOUT:
                return "wall-clock limit"
            case _:
                return self.value

    @property
    def reported(self) -> RunEnd:
        """How a run folder's report says this sweep status: a controller that finished
        (``ok``) ended the run as a program does (``program``); any other, as it is."""
        return RunEnd.PROGRAM if self is RunEnd.OK else self

    def as_result(self, exit_status: int | None) -> RunEnd:
        """How a sweep's results say a served run that ended so: the program's exit status
        decides ``ok`` or ``error``; a limit is itself; anything else is an ``error``."""
        if self is RunEnd.PROGRAM:
            return RunEnd.OK if exit_status == 0 else RunEnd.ERROR
        return self if self in (RunEnd.SECONDS, RunEnd.TIMEOUT) else RunEnd.ERROR

    @classmethod
    def words_for(cls, value: object) -> object:
        """``value`` (a report's ``ended_by``) in words if it is a :class:`RunEnd`; anything
        else (an edited report's) as it is."""
        if isinstance(value, str):
            with suppress(ValueError):
                return cls(value).words
        return value
