"""Start every transport a run serves, from the configuration plus command-line overrides."""

from __future__ import annotations

import ipaddress
import logging

from simmer.config.models import SimConfig
from simmer.errors import SimmerError
from simmer.options import RunOptions
from simmer.ports import PORT_RX, PORT_TX, STREAM_PORT, export_line
from simmer.transport.bus import ByteCounter, CommandBus
from simmer.transport.link import Link
from simmer.transport.rplidar_pty import RPLidarServer
from simmer.transport.serial_pty import SerialServer
from simmer.transport.tcp import StreamServer, TwoPortServer

log = logging.getLogger("simmer.transport")


def is_loopback(host: str) -> bool:
    """True for 127.x.x.x, ::1 and ``localhost``."""
    if host == "localhost":
        return True
    try:
        return ipaddress.ip_address(host).is_loopback
    except ValueError:
        return False


class Transports:
    """The two-port server, the stream server and (optionally) the virtual serial port, on the
    host and ports of ``options`` (the configuration's where they name none:
    :meth:`Ports.resolve <simmer.ports.Ports.resolve>`); the bytes they read and set aside are
    counted by ``clock`` (the runner's, so that a clock message's `` @N`` can wait for them;
    None: nowhere). With ``link_model`` every transport's command messages and replies cross
    it (:mod:`simmer.transport.link`)."""

    def __init__(
        self,
        bus: CommandBus,
        config: SimConfig,
        options: RunOptions | None = None,
        *,
        clock: ByteCounter | None = None,
        link_model: Link | None = None,
    ) -> None:
        settings = config.settings
        self.link_model = link_model
        options = options if options is not None else RunOptions()
        self.host = options.host if options.host is not None else settings.host
        self._by_hand = options.program is None
        """No program is started here: a moved port is told to other terminals."""
        port_rx, port_tx, stream_port = options.ports.resolve(settings.port_rx, settings.port_tx)
        if not is_loopback(self.host):
            log.warning(
                "listening on %s: any machine that can reach it can drive the robot", self.host
            )
        codec = config.reply_codec()
        self.protocol = codec.describe()
        network = options.box.network if options.box is not None else None
        listening = network.listeners if network is not None else None  # a box's own network
        self.two_port = TwoPortServer(
            bus,
            self.host,
            port_rx,
            port_tx,
            codec=codec,
            timeout=settings.timeout,
            clock=clock,
            link_model=link_model,
            listeners=listening[:2] if listening else None,
        )
        self.serial: SerialServer | None = None
        self.lidar: RPLidarServer | None = None
        try:
            self.stream = StreamServer(
                bus,
                self.host,
                stream_port,
                width=settings.reply_bytes,
                encoding=settings.str_encoding,
                timeout=settings.timeout,
                idle_timeout=settings.idle_timeout,
                lenient=settings.lenient_commands,
                clock=clock,
                link_model=link_model,
                listeners=listening[2:] if listening else None,
            )
            if options.serial or options.serial_link is not None:
                self.serial = SerialServer(
                    bus,
                    options.serial_link,
                    codec=codec,
                    timeout=settings.timeout,
                    clock=clock,
                    link_model=link_model,
                )
            if options.lidar_serial:
                lidars = [spec.id for spec in config.devices if spec.kind == "lidar"]
                if not lidars:
                    raise SimmerError(
                        "--lidar-serial: the robot has no LiDAR; add a sensor with "
                        'type = "lidar" to the configuration'
                    )
                self.lidar = RPLidarServer(bus, lidars[0], clock=clock)
        except BaseException:  # a port in use, a serial link refused, Ctrl-C: undo the rest
            self.close()
            raise

    def start(self) -> None:
        """Start serving on every transport."""
        self.two_port.start()
        self.stream.start()
        if self.serial is not None:
            self.serial.start()
        if self.lidar is not None:
            self.lidar.start()

    def describe(self) -> list[str]:
        """One line per transport: where a control program connects."""
        lines = [
            f"SimMeR two-port TCP: {self.host} rx {self.two_port.port_rx}, "
            f"tx {self.two_port.port_tx}; replies {self.protocol}",
            f"persistent TCP:      {self.host} port {self.stream.port} (simmer.client)",
        ]
        if self.serial is not None:
            link = f" (link {self.serial.link})" if self.serial.link else ""
            lines.append(f"virtual serial port: {self.serial.path}{link}; replies {self.protocol}")
        if self.link_model is not None:
            p = self.link_model.model.params
            drops = (
                f"dropouts of {p.dropout_seconds:g} s every {p.dropout_every:g} s on average"
                if p.dropout_every > 0 and p.dropout_seconds > 0
                else "no dropouts"
            )
            lines.append(
                f"link model {p.preset}: {p.baud:g} baud, latency {p.latency * 1000:g} ms "
                f"+ up to {p.jitter * 1000:g} ms, loss {p.loss:g} and corruption "
                f"{p.corruption:g} a byte, {drops} (docs/link.md)"
            )
        if self.lidar is not None:
            lines.append(
                f"virtual RPLidar:     {self.lidar.path} (LiDAR {self.lidar.device}, Slamtec's "
                "protocol: RPLidar(port).iter_scans())"
            )
        served = (self.two_port.port_rx, self.two_port.port_tx, self.stream.port)
        if self._by_hand and served != (PORT_RX, PORT_TX, STREAM_PORT):
            lines.append(export_line(*served))
        return lines

    def close(self) -> None:
        """Stop every transport."""
        servers = (self.two_port, getattr(self, "stream", None), self.serial, self.lidar)
        for server in servers:
            if server is not None:
                server.close()

    def __enter__(self) -> Transports:
        self.start()
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()
