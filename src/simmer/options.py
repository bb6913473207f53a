"""How a run is served: one frozen options object, made once and passed whole.

The command line (``simmer run``) makes it from the validated configuration and its own flags
(:meth:`RunOptions.for_config`); :func:`simmer.serve.serve`, the transports and the recorder
read what they need from it. A new option is one field here, not an edit to four signatures.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any, Literal

from simmer.ports import PORT_RX, PORT_TX, STREAM_PORT

if TYPE_CHECKING:
    from simmer.config.models import SimConfig

MAX_RECORDING_BYTES = 256 * 1024 * 1024
"""Bytes a recording's ``events.jsonl`` and ``trace.csv`` hold together (and the most of either
that is read back). An hour of a lockstep program sending a message every step is some 30 MB;
past the limit the recording stops (the run goes on) rather than fill the disk, and a replay
reads no file larger."""

Clock = Literal["realtime", "lockstep"]


@dataclass(frozen=True)
class RunOptions:
    """Everything about how one run is served (its configuration and seed aside).

    Ports: 0 is any free port (the start-up lines say which). ``speed`` is a multiple of real
    time, None as fast as possible. ``seconds`` (simulated) and ``timeout`` (wall, with a
    program) end the run. ``link_delay``: simulated seconds a message costs on the lockstep
    clock (None: one step)."""

    host: str = "127.0.0.1"
    port_rx: int = PORT_RX
    port_tx: int = PORT_TX
    stream_port: int = STREAM_PORT
    serial: bool = False
    serial_link: Path | None = None
    window: bool = False
    speed: float | None = 1.0
    clock: Clock = "realtime"
    link_delay: float | None = None
    seconds: float | None = None
    program: str | None = None
    answer: str | None = None
    """What the program reads at its prompt (its standard input: the text and a newline)."""
    timeout: float | None = None
    program_folder: Path | None = None
    """The program's working folder (None: this process's)."""
    program_output: int | None = None
    """A file descriptor the program's standard output and error go to (None: this
    process's own)."""
    record: Path | None = None
    record_limit: int = MAX_RECORDING_BYTES
    video: Path | None = None

    @classmethod
    def for_config(cls, config: SimConfig, **changes: Any) -> RunOptions:
        """The options of a run of ``config``: its host and two-port ports, then ``changes``."""
        s = config.settings
        return cls(host=s.host, port_rx=s.port_rx, port_tx=s.port_tx, **changes)

    @classmethod
    def free_ports(cls, **changes: Any) -> RunOptions:
        """Options on this machine's free ports (tests, sweeps: runs that share a machine)."""
        return cls(port_rx=0, port_tx=0, stream_port=0, **changes)

    @property
    def lockstep(self) -> bool:
        """Whether the lockstep clock decides the run."""
        return self.clock == "lockstep"

    def replace(self, **changes: Any) -> RunOptions:
        """A copy with ``changes``."""
        return dataclasses.replace(self, **changes)
