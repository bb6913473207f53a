"""How control programs reach the simulation: SimMeR's two-port scheme, the persistent
stream protocol and a virtual serial port. Everything goes through the :class:`CommandBus`; the
loop (:mod:`simmer.runner`) owns the simulation and also drives the TCP sockets (non-blocking,
watched through the bus), while the serial port has a thread that only reads, decodes and
queues. :class:`Transports` starts the transports a run asks for."""

from simmer.ports import STREAM_PORT
from simmer.transport.bus import CommandBus, Request
from simmer.transport.serial_pty import SerialServer
from simmer.transport.tcp import StreamServer, TwoPortServer
from simmer.transport.transports import Transports, is_loopback

__all__ = [
    "STREAM_PORT",
    "CommandBus",
    "Request",
    "SerialServer",
    "StreamServer",
    "Transports",
    "TwoPortServer",
    "is_loopback",
]
