"""How control programs reach the simulation: SimMeR's two-port scheme, the persistent
stream protocol and a virtual serial port. Transport threads only read, decode and queue on the
:class:`CommandBus`; the loop (:mod:`simmer.runner`) owns the simulation and also serves the
persistent protocol's sockets directly. :class:`Link` starts the transports a run asks for."""

from simmer.transport.bus import BusClosed, CommandBus, Request
from simmer.transport.link import Link, is_loopback
from simmer.transport.serial_pty import SerialServer
from simmer.transport.tcp import STREAM_PORT, StreamServer, TwoPortServer

__all__ = [
    "STREAM_PORT",
    "BusClosed",
    "CommandBus",
    "Link",
    "Request",
    "SerialServer",
    "StreamServer",
    "TwoPortServer",
    "is_loopback",
]
