"""``simmer console``: type commands, see the replies (the lab's interactive client).

Works over any :mod:`simmer.client` connection: the persistent protocol, SimMeR's two-port
scheme or a serial port (the simulator's virtual one or the robot's). Line editing and history
come from the standard library's readline where it is available.
"""

from __future__ import annotations

import contextlib
import math
from collections.abc import Callable
from pathlib import Path

from simmer.client import Client
from simmer.errors import ClientError

HISTORY = Path.home() / ".simmer_history"
HELP = (
    "Commands: u0 (read a sensor), w0-6 (drive 6 in), w0--6 (back), r0-90 (turn), xx (stop),\n"
    "several at once with commas: u0,u1,u2,u3. Replies: +inf accepted, nan rejected or invalid.\n"
    "Type 'quit' (or Ctrl-D) to leave."
)


def format_reply(value: float) -> str:
    """A reply value as a student reads it."""
    if math.isnan(value):
        return "nan"
    if math.isinf(value):
        return "+inf (accepted)" if value > 0 else "-inf"
    return f"{value:.3f}"


def _enable_history() -> Callable[[], None]:
    """Turn on readline history (if present); returns a function that saves it."""
    try:
        import readline
    except ImportError:  # e.g. Windows without pyreadline
        return lambda: None
    with contextlib.suppress(OSError):
        readline.read_history_file(HISTORY)
    readline.set_history_length(1000)

    def save() -> None:
        with contextlib.suppress(OSError):
            readline.write_history_file(HISTORY)

    return save


def run_console(
    client: Client,
    *,
    read: Callable[[str], str] = input,
    echo: Callable[[str], None] = print,
    history: bool = True,
) -> None:
    """Read commands until 'quit' or end of input, printing each reply."""
    save = _enable_history() if history else (lambda: None)
    echo(HELP)
    try:
        while True:
            try:
                line = read("simmer> ").strip()
            except EOFError:
                break
            if line in ("quit", "exit"):
                break
            if not line:
                continue
            try:
                replies = client.send(line)
            except ClientError as exc:
                echo(f"error: {exc}")
                continue
            commands = line.split(",")
            echo(
                "  ".join(
                    f"{c.strip()}: {format_reply(v)}"
                    for c, v in zip(commands, replies, strict=False)
                )
            )
    finally:
        save()
