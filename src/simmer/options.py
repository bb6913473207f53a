"""How a run is served: one frozen options object, made once and passed whole.

The command line (``simmer run``) makes it from its flags (:meth:`RunOptions.from_flags`, which
holds every decision ``run`` makes about them, without typer); :func:`simmer.serve.serve`, the
transports and the recorder read what they need from it. A new option is one field here, not an
edit to four signatures.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any, Literal

from simmer.errors import FlagError, PortsError
from simmer.ports import Ports, environment_ports, parse_ports

if TYPE_CHECKING:
    from simmer.lockstep.box import Box

MAX_RECORDING_BYTES = 256 * 1024 * 1024
"""Bytes a recording's ``events.jsonl`` and ``trace.csv`` hold together (and the most of either
that is read back). An hour of a lockstep program sending a message every step is some 30 MB;
past the limit the recording stops (the run goes on) rather than fill the disk, and a replay
reads no file larger."""
SPEED_RANGE = (0.01, 1000.0)
"""``--speed`` as a multiple of real time, 'max' aside: the window's keys go from 1/8 to 32; a
speed of 1e-300 never took a second step, and above 1,000 only 'max' is faster."""

Clock = Literal["realtime", "lockstep"]


def parse_speed(text: str) -> float | None:
    """``"max"`` -> None (as fast as possible); otherwise a positive multiple of real time."""
    if text.strip().lower() == "max":
        return None
    try:
        value = float(text)
    except ValueError:
        raise ValueError(f"speed is a number (1 = real time) or 'max', not {text!r}") from None
    if not value > 0 or value == float("inf"):
        raise ValueError(f"speed must be more than 0, not {text!r}")
    return value


@dataclass(frozen=True)
class RunOptions:
    """Everything about how one run is served (its configuration and seed aside).

    ``host`` None and ``ports`` None are the configuration's (:class:`~simmer.ports.Ports`
    says which ports, and which are free). ``speed`` is a multiple of real time, None as fast
    as possible. ``seconds`` (simulated) and ``timeout`` (wall, with a program) end the run.
    ``link_delay``: simulated seconds a message costs on the lockstep clock (None: one step)."""

    host: str | None = None
    ports: Ports = field(default_factory=Ports)
    serial: bool = False
    serial_link: Path | None = None
    lidar_serial: bool = False
    """Serve the robot's LiDAR as a virtual RPLidar on a pseudo-terminal."""
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
    box: Box | None = None
    """Run the program in this box (:mod:`simmer.lockstep.box`; a graded team's)."""
    record: Path | None = None
    record_limit: int = MAX_RECORDING_BYTES
    video: Path | None = None

    @classmethod
    def from_flags(
        cls,
        *,
        headless: bool = False,
        speed: str | None = None,
        clock: str | None = None,
        program: str | None = None,
        answer: str | None = None,
        port_rx: int | None = None,
        port_tx: int | None = None,
        port: int | None = None,
        ports: str | None = None,
        environ: Mapping[str, str] | None = None,
        serial: bool = False,
        serial_link: Path | None = None,
        lidar_serial: bool = False,
        link_delay: float | None = None,
        seconds: float | None = None,
        timeout: float | None = None,
        record: Path | None = None,
        record_limit_mb: float = MAX_RECORDING_BYTES / 2**20,
        video: Path | None = None,
    ) -> RunOptions:
        """The options of ``simmer run`` with these flags (None: not given), and the decisions
        it makes about them: a program's run is on the lockstep clock and this run's own free
        ports, and (headless) as fast as possible, unless the flags say otherwise; ``--speed``
        is 'max' or within :data:`SPEED_RANGE`; ``--answer`` needs a program and is at most
        :data:`~simmer.lockstep.MAX_ANSWER` characters. Raises :class:`FlagError` naming the
        flag it refuses.

        ``ports`` (``--ports``: ``auto``, ``N`` or ``RX,TX,PORT``) moves all three ports at
        once; without it ``SIMMER_PORTS`` in ``environ`` (default: this process's) does, except
        for a program's run, which keeps to free ports of its own; ``--port-rx``, ``--port-tx``
        and ``--port`` still name one each, over either."""
        from simmer.lockstep import MAX_ANSWER

        if speed is None:
            speed = "max" if headless and program else "1"
        pace = _pace(speed)
        if clock not in (None, "realtime", "lockstep"):
            raise FlagError(f"realtime or lockstep, not {clock!r}", "--clock")
        lockstep = clock == "lockstep" if clock else bool(program)
        if answer is not None and program is None:
            raise FlagError("what --program reads at its prompt: give --program too")
        if answer is not None and len(answer) > MAX_ANSWER:
            raise FlagError(
                f"{len(answer):,} characters; at most {MAX_ANSWER:,} (a few typed lines)",
                "--answer",
            )
        try:
            chosen = (
                parse_ports(ports)
                if ports is not None
                else None
                if program
                else environment_ports(environ)
            )
        except PortsError as exc:
            raise FlagError(str(exc)) from None
        return cls(
            ports=Ports.from_flags(
                port_rx, port_tx, port, program=program is not None, chosen=chosen
            ),
            serial=serial,
            serial_link=serial_link,
            lidar_serial=lidar_serial,
            window=not headless,
            speed=pace,
            clock="lockstep" if lockstep else "realtime",
            link_delay=link_delay,
            seconds=seconds,
            program=program,
            answer=answer,
            timeout=timeout,
            record=record,
            record_limit=int(record_limit_mb * 2**20),
            video=video,
        )

    @classmethod
    def free_ports(cls, **changes: Any) -> RunOptions:
        """Options on this machine's free ports (tests, sweeps: runs that share a machine)."""
        return cls(ports=Ports.free(), **changes)

    @property
    def lockstep(self) -> bool:
        """Whether the lockstep clock decides the run."""
        return self.clock == "lockstep"

    def for_target(self, target: str | None) -> RunOptions:
        """The options of a run whose target zone is ``target``: '{target}' in ``answer``
        becomes it (what a student types at the program's prompt is the run's drawn zone)."""
        if self.answer is None or target is None:
            return self
        return self.replace(answer=self.answer.replace("{target}", target))

    def replace(self, **changes: Any) -> RunOptions:
        """A copy with ``changes``."""
        return dataclasses.replace(self, **changes)


def _pace(speed: str) -> float | None:
    """``--speed``: 'max' (None) or a multiple of real time within :data:`SPEED_RANGE`."""
    try:
        pace = parse_speed(speed)
    except ValueError as exc:
        raise FlagError(str(exc), "--speed") from None
    low, high = SPEED_RANGE
    if pace is not None and not low <= pace <= high:
        raise FlagError(
            f"{speed}: from {low:g} to {high:g} times real time, or 'max' (SPEED_RANGE; "
            "SimMeR's limits are in docs/limits.md)",
            "--speed",
        )
    return pace
