"""A control program's printout, passed through SimMeR to the terminal.

``simmer run --program`` gives the program pipes for its standard output and error and copies
each to SimMeR's own as it comes, a partial line too (an ``input()`` prompt shows before the
program waits for its answer). SimMeR says nothing on them while the program runs, so the
two never share a line; when the run ends, :meth:`ProgramOutput.finish` waits for the copies
to reach the end of the pipes and ends a last line the program left open, so SimMeR's own
end-of-run lines start on a line of their own, the same in every run.
"""

from __future__ import annotations

import codecs
import logging
import os
import subprocess
import threading
from typing import IO, TextIO

log = logging.getLogger("simmer.lockstep")

DRAIN_SECONDS = 2.0
"""Wall seconds :meth:`ProgramOutput.finish` waits, once the program and every process it
started are stopped, for its pipes to end. They end at once unless a process that escaped
the clean-up still holds one; past this, what such a process writes is not shown."""

CHUNK = 65_536
"""Most bytes copied at a time: what one read of a pipe gives."""

ENCODING = "utf-8"
"""What the program writes in: ``simmer run`` gives it ``PYTHONIOENCODING=utf-8`` unless the
environment says otherwise, so that its text reads right on any terminal (a Windows pipe
would otherwise get the ANSI code page)."""


class _Copy:
    """One pipe copied to ``target`` as it comes, in a thread of its own."""

    def __init__(self, source: IO[bytes], target: TextIO) -> None:
        self.source = source
        self.target = target
        self.last = b""
        """The last byte written to ``target`` (empty: nothing yet)."""
        self.closed = False
        """No more is written (the run's own lines come next)."""
        self.lock = threading.Lock()
        self._encoding = getattr(target, "encoding", None) or ENCODING
        self._same = codecs.lookup(self._encoding).name == codecs.lookup(ENCODING).name
        self._decoder = codecs.getincrementaldecoder(ENCODING)(errors="replace")
        self.thread = threading.Thread(target=self._run, name="simmer-program-output", daemon=True)
        self.thread.start()

    def _run(self) -> None:
        descriptor = self.source.fileno()
        try:
            while data := os.read(descriptor, CHUNK):
                self._write(data)
        except OSError as exc:  # the target went away (a closed terminal): stop copying
            log.warning("the program's output could not be shown: %s", exc)
        finally:
            self.source.close()

    def _write(self, data: bytes) -> None:
        """``data`` on ``target`` now, as bytes if it takes the program's encoding."""
        with self.lock:
            if self.closed:
                return
            self.target.flush()  # anything of SimMeR's written before goes first
            buffer = getattr(self.target, "buffer", None)
            if buffer is not None and self._same:
                buffer.write(data)
                buffer.flush()
            else:
                text = self._decoder.decode(data)
                if buffer is not None:
                    buffer.write(text.encode(self._encoding, errors="replace"))
                    buffer.flush()
                else:
                    self.target.write(text)
                    self.target.flush()
            self.last = data[-1:]

    def finish(self, timeout: float) -> None:
        """Wait up to ``timeout`` s for the end of the pipe, stop copying, and end the last
        line if the program left it open."""
        self.thread.join(timeout)
        if self.thread.is_alive():
            log.warning(
                "the program's output was still open %g s after it ended (a process it "
                "started holds it): what it writes now is not shown (DRAIN_SECONDS)",
                timeout,
            )
        with self.lock:
            self.closed = True
            if self.last not in (b"", b"\n"):
                self.target.write("\n")
                self.target.flush()
                self.last = b"\n"


class ProgramOutput:
    """The program's standard output and error, each copied to SimMeR's own (see the module
    doc); :meth:`finish` once the program and what it started are stopped."""

    def __init__(self, process: subprocess.Popen[bytes], stdout: TextIO, stderr: TextIO) -> None:
        self._copies = [
            _Copy(source, target)
            for source, target in ((process.stdout, stdout), (process.stderr, stderr))
            if source is not None
        ]

    def finish(self, timeout: float = DRAIN_SECONDS) -> None:
        """Copy what is left in the pipes (waiting at most ``timeout`` s for their end), then
        end any last line the program left open."""
        for copy in self._copies:
            copy.finish(timeout)
