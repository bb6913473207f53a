"""``simmer console``: commands typed to a running simulator, and its replies."""

from __future__ import annotations

from typing import Annotated

import typer

from simmer.cli.app import Command, app, err, example


@app.command(
    cls=Command,
    short_help="Type commands (u0, w0-6) and see the replies.",
    epilog=example("simmer console          (then type u0,u1,u2,u3 or w0-6; help lists them)"),
)
def console(
    host: Annotated[
        str | None,
        typer.Option(
            help="Simulator address (default: SIMMER_HOST, else 127.0.0.1).",
            show_default=False,
            metavar="ADDRESS",
        ),
    ] = None,
    port: Annotated[
        int | None,
        typer.Option(
            help="Persistent protocol port (default: as --ports says).",
            show_default=False,
            min=1,
            max=65535,
            metavar="PORT",
        ),
    ] = None,
    ports: Annotated[
        str | None,
        typer.Option(
            "--ports",
            help="The simulator's three ports, as simmer run --ports names them: N (N, N+1, "
            "N+2) or RX,TX,PORT (default: SIMMER_PORTS if set, else 61200, 61201, 61202).",
            show_default=False,
            metavar="N|RX,TX,PORT",
        ),
    ] = None,
    two_port: Annotated[
        bool,
        typer.Option(
            "--two-port",
            help="Use SimMeR's two-port scheme (ports RX and TX of --ports) instead.",
        ),
    ] = False,
    serial: Annotated[
        str | None,
        typer.Option(
            help="Talk to a serial port (virtual or the robot's) instead.", metavar="PORT"
        ),
    ] = None,
    baud: Annotated[int, typer.Option(help="Serial baud rate.", metavar="BAUD")] = 9600,
    framed: Annotated[
        bool,
        typer.Option(
            "--framed",
            help="Speak SimMeR v1.2's framed text ([u0] -> [u0:15.45]) over the two-port "
            "scheme or --serial, as a simulator with protocol = 'framed' (a v1.2 config.py) does.",
        ),
    ] = False,
) -> None:
    """Interactive console: type commands (u0, w0-6, ...) and see the replies."""
    from simmer.client import connect
    from simmer.console import run_console
    from simmer.errors import ClientError, PortsError
    from simmer.ports import AUTO, parse_ports

    port_rx = port_tx = None
    if ports is not None:
        try:
            if ports.strip().lower() == AUTO:
                raise PortsError(
                    "--ports auto is for simmer run; give the ports it printed (e.g. 62000)"
                )
            chosen = parse_ports(ports)
        except PortsError as exc:
            message = str(exc).removeprefix("--ports=")
            raise typer.BadParameter(message, param_hint="--ports") from None
        port_rx, port_tx = chosen.rx, chosen.tx
        port = chosen.stream if port is None else port
    try:
        client = connect(
            host,
            port,
            port_rx=port_rx,
            port_tx=port_tx,
            scheme="two-port" if two_port else None,
            serial=serial,
            baudrate=baud,
            framed=framed,
        )
    except ClientError as exc:
        err.print(str(exc), style="bold red")
        raise typer.Exit(1) from None
    with client:
        run_console(client)
