"""The command language, as pure functions: text in, commands out (BEHAVIOUR §6).

A message is one or more commands separated by commas (``u0,u1,w0-12``). A command is a
two-character device id, optionally followed by ``-`` and a decimal number (``w0--6`` moves
back 6 in); a bare id means value 0. Anything else is a malformed command: it is answered with
NaN and the reason is logged, instead of SimMeR's silent 0.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass

STOP_ID = "xx"
SEPARATOR = "-"
MAX_ABS_VALUE = 1e9
_NUMBER = re.compile(r"[+-]?(?:\d+(?:\.\d*)?|\.\d+)(?:[eE][+-]?\d+)?")


@dataclass(frozen=True)
class Command:
    """One parsed command. ``error`` is set (and the reply will be NaN) if it is malformed."""

    text: str
    device: str = ""
    value: float = 0.0
    error: str | None = None


def parse_command(text: str) -> Command:
    """Parse one command such as ``w0-6``, ``u0`` or ``r0--90``."""
    stripped = text.strip()
    if not stripped:
        return Command(text, error="empty command")
    if len(stripped) < 2:
        return Command(text, error=f"{stripped!r} is too short: a device id has two characters")
    device = stripped[:2]
    if len(stripped) == 2:
        return Command(text, device, 0.0)
    if stripped[2] != SEPARATOR:
        return Command(
            text,
            device,
            error=f"expected '{SEPARATOR}' after the device id {device!r}, "
            f"got {stripped[2]!r} (write e.g. '{device}-5')",
        )
    raw = stripped[3:]
    if not _NUMBER.fullmatch(raw):
        return Command(text, device, error=f"{raw!r} is not a decimal number")
    value = float(raw)
    if not math.isfinite(value) or abs(value) > MAX_ABS_VALUE:
        return Command(text, device, error=f"{raw!r} is out of range (at most ±{MAX_ABS_VALUE:g})")
    return Command(text, device, value)


def parse_message(text: str) -> list[Command]:
    """Split a message on commas and parse each command; an empty message is one bad command."""
    return [parse_command(part) for part in text.strip().split(",")]
