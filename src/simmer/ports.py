"""SimMeR's standard ports, written in one place (the original's, and the persistent one), and
the one type that decides which ports a run listens on (:class:`Ports`)."""

from __future__ import annotations

from dataclasses import dataclass

PORT_RX = 61200
"""SimMeR's two-port scheme: messages arrive here (a client transmits to it)."""
PORT_TX = 61201
"""SimMeR's two-port scheme: replies leave from here (a client receives from it)."""
STREAM_PORT = 61202
"""The persistent protocol (``simmer.client``)."""
FREE = 0
"""A port that is any free one the system gives when the run listens (the start-up lines say
which): a program's, a sweep's or a test's run, so that runs can share a machine."""


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
        cls, rx: int | None, tx: int | None, stream: int | None, *, program: bool
    ) -> Ports:
        """The ports of ``simmer run --port-rx --port-tx --port`` (None: not given): with a
        ``program``, one not given is free (the run's own ports, which the program is sent to),
        otherwise the configuration's."""
        if program:
            return cls(*(FREE if port is None else port for port in (rx, tx, stream)))
        return cls(rx, tx, stream)

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
