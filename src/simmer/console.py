"""``simmer console``: type commands, see the replies (the lab's interactive client).

Works over any :mod:`simmer.client` connection: the persistent protocol, SimMeR's two-port
scheme or a serial port (the simulator's virtual one or the robot's). Replies are shown in the
form in use: numbers for packed replies; for SimMeR v1.2's framed text (``--framed``) the reply
as sent (``[u0:15.45,w0:True]``), like the stock v1.2 client, with a warning when an entry's id
is not the command's; over the persistent protocol a NaN reply is followed by the simulator's
reason. Line editing and history come from readline where it is available;
``help`` (or ``?``) prints the help again.
"""

from __future__ import annotations

import contextlib
import math
from collections.abc import Callable
from pathlib import Path

from simmer.client import Client
from simmer.errors import ClientError
from simmer.protocol import command_ids, read_framed_reply

HISTORY = Path.home() / ".simmer_history"
LOCAL_HELP = ("help", "?")
"""What the console answers itself with :data:`HELP` instead of sending it to the simulator."""
HELP = (
    "Commands: u0 (read a sensor), w0-6 (drive 6 in), w0--6 (back), r0-90 (turn), xx (stop),\n"
    "several at once with commas: u0,u1,u2,u3. Replies: +inf accepted, nan rejected or invalid.\n"
    "Type 'help' (or ?) to see this again, 'quit' (or Ctrl-D) to leave."
)


def format_reply(value: float) -> str:
    """A reply value as a student reads it."""
    if math.isnan(value):
        return "nan"
    if math.isinf(value):
        return "+inf (accepted)" if value > 0 else "-inf"
    return f"{value:.3f}"


def format_exchange(message: str, replies: list[float]) -> str:
    """Each command of ``message`` beside its packed reply value."""
    commands = message.split(",")
    return "  ".join(
        f"{c.strip()}: {format_reply(v)}" for c, v in zip(commands, replies, strict=False)
    )


def format_framed(message: str, text: str) -> str:
    """A framed reply as sent, then a line per entry whose id is not its command's."""
    lines = [text]
    ids = command_ids(message)
    for index, (device_id, _) in enumerate(read_framed_reply(text)):
        wanted = ids[index] if index < len(ids) else None
        if device_id != wanted:
            lines.append(f"  entry {index + 1} is for {device_id!r}; the command was {wanted!r}")
    return "\n".join(lines)


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
            if line.lower() in LOCAL_HELP:
                echo(HELP)
                continue
            if not line:
                continue
            try:
                replies = client.send(line)
            except ClientError as exc:
                echo(f"error: {exc}")
                continue
            text = client.link.last_text
            echo(format_exchange(line, replies) if text is None else format_framed(line, text))
            if text is None and any(map(math.isnan, replies)):
                with contextlib.suppress(ClientError):  # the next command reports a lost link
                    if why := client.explain():  # the simulator's reasons (persistent only)
                        echo("  why: " + why.replace("\n", "\n       "))
    finally:
        save()
