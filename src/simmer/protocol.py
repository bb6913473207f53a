"""The command language, as pure functions: text in, commands out (BEHAVIOUR §6).

A message is one or more commands separated by commas (``u0,u1,w0-12``). A command is a
two-character device id, optionally followed by ``-`` and a decimal number (``w0--6`` moves
back 6 in); a bare id means value 0. Anything else is a malformed command: it is answered with
NaN and the reason is logged, instead of SimMeR's silent 0.

The second half is the byte level shared by every transport: decoding a received message
(non-text bytes become NaN replies, never a dead listener), packing replies as little-endian
float32/float64, and the persistent protocol's reply frame (docs/protocol.md).
"""

from __future__ import annotations

import math
import re
import struct
from collections.abc import Sequence
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


# --------------------------------------------------------------------------- bytes and framing

MAX_MESSAGE_BYTES = 64 * 1024
"""Longest message accepted, in bytes (without its line ending)."""

REPLY_FORMATS = {4: "<f", 8: "<d"}
"""``struct`` format of one reply value by width: float32 (SimMeR 1.1, Arduino) or float64."""

FRAME_HEADER = struct.Struct("<BH")
"""Persistent-protocol reply header: value width in bytes (4 or 8), then the value count."""


@dataclass(frozen=True)
class Decoded:
    """A message as received: its text, or (``text is None``) why it cannot be executed.

    ``count`` is how many NaN replies an undecodable message gets: one per comma-separated
    command, so a client still receives exactly one value per command it sent.
    """

    text: str | None
    count: int = 1
    error: str | None = None


def decode_message(data: bytes, encoding: str = "utf-8") -> Decoded:
    """Decode the bytes of one message (line ending already removed, or not)."""
    if len(data) > MAX_MESSAGE_BYTES:
        return Decoded(None, 1, f"message of {len(data)} bytes is over {MAX_MESSAGE_BYTES}")
    count = data.count(b",") + 1
    try:
        text = data.decode(encoding)
    except UnicodeDecodeError as exc:
        return Decoded(None, count, f"not {encoding} text ({exc.reason} at byte {exc.start})")
    return Decoded(text.rstrip("\r\n"), count)


def pack_replies(values: Sequence[float], width: int = 4) -> bytes:
    """Pack reply values as little-endian floats of ``width`` bytes (4 or 8), no framing."""
    fmt = REPLY_FORMATS[width]
    return struct.pack(f"<{len(values)}{fmt[1]}", *values)


def unpack_replies(data: bytes, width: int = 4) -> list[float]:
    """Inverse of :func:`pack_replies`; ``len(data)`` must be a multiple of ``width``."""
    if len(data) % width:
        raise ValueError(f"{len(data)} bytes is not a whole number of {width}-byte values")
    fmt = REPLY_FORMATS[width]
    return list(struct.unpack(f"<{len(data) // width}{fmt[1]}", data))


def frame_replies(values: Sequence[float], width: int = 4) -> bytes:
    """Persistent protocol: header (width, count) followed by the packed values."""
    return FRAME_HEADER.pack(width, len(values)) + pack_replies(values, width)


def read_frame_header(header: bytes) -> tuple[int, int]:
    """Parse a persistent-protocol reply header; returns (width, count)."""
    width, count = FRAME_HEADER.unpack(header)
    if width not in REPLY_FORMATS:
        raise ValueError(f"bad reply header: value width {width} (expected 4 or 8)")
    return width, count
