"""``simmer tap``: between a program and the robot's port, recording the real run."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from simmer.cli.app import Command, app, err, example, out
from simmer.cli.common import report_config_error


@app.command(
    cls=Command,
    short_help="Record the real robot: sit between your program and its port.",
    epilog=example(
        'simmer tap /dev/rfcomm0 --config robot.toml --record runs/real1 --program "python '
        'my_robot.py {port}"',
        "simmer tap COM5 --config robot.toml --record runs/real2   (then open the printed port)",
        "simmer tap tcp://127.0.0.1:61202 --config robot.toml --record runs/sim1",
    ),
)
def tap(
    target: Annotated[
        str,
        typer.Argument(
            help="The robot's port: its serial device (/dev/rfcomm0, /dev/tty.HC-05, COM5) or "
            "tcp://HOST:PORT for an endpoint speaking a SimMeR protocol as a stream.",
            metavar="PORT",
        ),
    ],
    config: Annotated[
        Path,
        typer.Option(
            "--config",
            help="The robot's configuration: its protocol, maze and devices.",
            metavar="CONFIG",
        ),
    ],
    record: Annotated[
        Path,
        typer.Option(
            "--record", help="The new run folder to write the real run into.", metavar="DIR"
        ),
    ],
    program: Annotated[
        str | None,
        typer.Option(
            help="Start this program with {port} replaced by the tap's port (also in "
            "SIMMER_TAP_PORT); the tap ends when it exits. Without it: Ctrl-C ends the tap.",
            metavar="COMMAND",
        ),
    ] = None,
    link: Annotated[
        Path | None,
        typer.Option(
            help="Also make this symbolic link to the tap's port (a stable name).", metavar="PATH"
        ),
    ] = None,
    baud: Annotated[
        int, typer.Option(help="The robot port's baud rate.", min=1, metavar="BAUD")
    ] = 9600,
) -> None:
    """Sit between a control program and the robot: the program opens the tap's port (printed)
    instead of the robot's, every byte is forwarded both ways unchanged, and each command and
    reply is recorded in DIR with wall-clock times (no true pose: it is the real robot). simmer
    plot, replay, calibrate and compare read the folder. If the robot goes (its port closes),
    the tap keeps what it recorded and says so."""
    import shlex
    import signal
    import threading

    from simmer.config import load_config
    from simmer.errors import ConfigError, TapError
    from simmer.tap.session import Tap

    try:
        settings = load_config(config)
    except ConfigError as exc:
        report_config_error(exc)
        raise typer.Exit(1) from None
    argv = shlex.split(program) if program else None
    try:
        session = Tap(settings, target, record, link=link, baudrate=baud)
    except TapError as exc:
        err.print(str(exc), style="bold red", markup=False)
        raise typer.Exit(1) from None
    stop = threading.Event()
    for number in (signal.SIGINT, signal.SIGTERM):
        signal.signal(number, lambda *_: stop.set())
    shown = f" (and {link})" if link else ""
    result = session.run(
        argv,
        stop,
        on_ready=lambda path: out.print(
            f"tap port: {path}{shown} -> {target}; recording into {record}", markup=False
        ),
    )
    out.print(
        f"{result.ended}; recorded {result.exchanges} exchanges in {result.folder}"
        + (f" ({result.unanswered} never answered)" if result.unanswered else ""),
        markup=False,
    )
    if result.robot_lost:
        err.print(
            "the robot was lost: what came before is recorded; check its power and link",
            style="bold red",
            markup=False,
        )
        raise typer.Exit(2)
