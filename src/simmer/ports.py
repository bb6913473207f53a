"""SimMeR's standard ports, written in one place (the original's, and the persistent one), and
the one type that decides which ports a run listens on (:class:`Ports`)."""

from __future__ import annotations

import os
from collections.abc import Mapping
from dataclasses import dataclass

from simmer.errors import PortsError

PORT_RX = 61200
"""SimMeR's two-port scheme: messages arrive here (a client transmits to it)."""
PORT_TX = 61201
"""SimMeR's two-port scheme: replies leave from here (a client receives from it)."""
STREAM_PORT = 61202
"""The persistent protocol (``simmer.client``)."""
FREE = 0
"""A port that is any free one the system gives when the run listens (the start-up lines say
which): a program's, a sweep's or a test's run, so that runs can share a machine."""


PORTS_VARIABLE = "SIMMER_PORTS"
"""The environment variable every command, the client library and the examples read for the
three ports (:func:`parse_ports`): set once in a terminal, ``simmer run``, ``simmer console``
and a program started there all move together."""
AUTO = "auto"
"""``--ports auto`` (or ``SIMMER_PORTS=auto`` for ``simmer run``): three free ports, printed."""


@dataclass(frozen=True)
class Ports:
    """The ports one run listens on (:attr:`simmer.options.RunOptions.ports`): each a number,
    :data:`FREE`, or None for the configuration's (its ``port_rx`` and ``port_tx`` settings;
    the persistent port has no setting: :data:`STREAM_PORT`)."""

    rx: int | None = None
    """The two-port scheme's message port."""
    tx: int | None = None
    """The two-port scheme's reply port."""
    stream: int | None = None
    """The persistent protocol's port."""

    @classmethod
    def free(cls) -> Ports:
        """Every port free."""
        return cls(FREE, FREE, FREE)

    @classmethod
    def from_flags(
        cls,
        rx: int | None,
        tx: int | None,
        stream: int | None,
        *,
        program: bool,
        chosen: Ports | None = None,
    ) -> Ports:
        """The ports of ``simmer run --port-rx --port-tx --port`` (None: not given) over the
        ``chosen`` three (``--ports`` or ``SIMMER_PORTS``): a flag naming one port wins; one
        neither names is, with a ``program``, free (the run's own ports, which the program is
        sent to), otherwise the configuration's."""
        base = chosen if chosen is not None else (cls.free() if program else cls())
        return cls(
            base.rx if rx is None else rx,
            base.tx if tx is None else tx,
            base.stream if stream is None else stream,
        )

    def settings(self) -> dict[str, int]:
        """The two-port numbers named here as configuration settings (``port_rx``,
        ``port_tx``), so that they are checked as a file's are (two equal ports are refused
        before any port opens) and a recording's configuration keeps them; a free port and
        the configuration's own are no setting."""
        named = (("port_rx", self.rx), ("port_tx", self.tx))
        return {key: port for key, port in named if port is not None and port != FREE}

    def resolve(self, port_rx: int, port_tx: int) -> tuple[int, int, int]:
        """The numbers to listen on (two-port message and reply, persistent), given the
        configuration's ``port_rx`` and ``port_tx``: a :data:`FREE` one stays 0, which the
        system's ``bind`` makes a free port."""
        return (
            port_rx if self.rx is None else self.rx,
            port_tx if self.tx is None else self.tx,
            STREAM_PORT if self.stream is None else self.stream,
        )


def parse_ports(text: str, where: str = "--ports") -> Ports:
    """The ports ``text`` names: ``auto`` (three free ones), one number ``N`` (``N``, ``N+1``
    and ``N+2``: message, reply and persistent, as 61200 names SimMeR's own) or three numbers
    ``RX,TX,PORT``. ``where`` names the flag or variable in the error (:class:`PortsError`)."""
    given = text.strip()
    if given.lower() == AUTO:
        return Ports.free()
    parts = [part.strip() for part in given.split(",")]
    fix = "write one port (e.g. 62000 for 62000, 62001, 62002), three (62000,62001,62002) or auto"
    if len(parts) not in (1, 3) or not all(part.isdigit() for part in parts):
        raise PortsError(f"{where}={text!r}: not ports; {fix}")
    numbers = [int(part) for part in parts]
    if len(numbers) == 1:
        numbers = [numbers[0] + step for step in range(3)]
    if not all(1 <= number <= 65535 for number in numbers):
        raise PortsError(f"{where}={text!r}: each port is from 1 to 65535; {fix}")
    if len(set(numbers)) != 3:
        raise PortsError(f"{where}={text!r}: the three ports must differ; {fix}")
    return Ports(*numbers)


def environment_ports(environ: Mapping[str, str] | None = None) -> Ports | None:
    """The ports ``SIMMER_PORTS`` names in ``environ`` (default: this process's), None if it
    is unset or empty; raises :class:`PortsError` naming the variable if it names none."""
    text = (os.environ if environ is None else environ).get(PORTS_VARIABLE, "")
    return parse_ports(text, PORTS_VARIABLE) if text.strip() else None


def export_line(rx: int, tx: int, stream: int) -> str:
    """How to give other terminals these ports: the variable's setting in bash and in
    PowerShell (a line ``simmer run`` prints when it listens elsewhere than SimMeR's own)."""
    value = f"{rx},{tx},{stream}"
    return (
        f"other terminals: export {PORTS_VARIABLE}={value}  "
        f'(PowerShell: $env:{PORTS_VARIABLE}="{value}"; cmd: set {PORTS_VARIABLE}={value})'
    )
