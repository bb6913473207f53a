"""How control programs reach the simulation: SimMeR's two-port scheme, the persistent
stream protocol and a virtual serial port. Everything goes through the :class:`CommandBus` (a
:class:`~simmer.transport.loop.SelectorLoop` and a
:class:`~simmer.transport.request_queue.RequestQueue`); the loop (:mod:`simmer.runner`) owns
the simulation and also drives the TCP sockets and the serial port (non-blocking, watched
through the bus). :class:`Transports` starts the transports a run asks for."""

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
