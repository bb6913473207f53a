"""``simmer console``: commands typed to a running simulator, and its replies."""

from __future__ import annotations

from typing import Annotated

import typer

from simmer.cli.app import Command, app, err, example
from simmer.ports import STREAM_PORT


@app.command(
    cls=Command,
    short_help="Type commands (u0, w0-6) and see the replies.",
    epilog=example("simmer console          (then type u0,u1,u2,u3 or w0-6; help lists them)"),
)
def console(
    host: Annotated[str, typer.Option(help="Simulator address.", metavar="ADDRESS")] = (
        "127.0.0.1"
    ),
    port: Annotated[
        int, typer.Option(help="Persistent protocol port.", metavar="PORT")
    ] = STREAM_PORT,
    two_port: Annotated[
        bool,
        typer.Option("--two-port", help="Use SimMeR's two-port scheme (61200/61201) instead."),
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
    from simmer.errors import ClientError

    try:
        client = connect(
            host,
            port,
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
